//! `meshlight-gallery [--tile T] [--sphere-detail N] [--out DIR]`: writes the gallery's OBJ
//! (into scenes/gallery by default; elsewhere with its scene.toml and gallery.mtl beside it).

use std::path::PathBuf;
use std::process::ExitCode;

use meshlight_gallery::{shipped_dir, write_obj, GalleryOptions};

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("meshlight-gallery: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let mut options = GalleryOptions::default();
    let mut out = shipped_dir();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--tile" => {
                let v = value("--tile")?;
                options.tile = v
                    .parse()
                    .map_err(|_| format!("--tile: '{v}' is not a number"))?;
                if !(options.tile > 0.0 && options.tile <= 4.5) {
                    return Err(format!("--tile {v}: must be in (0, 4.5] metres"));
                }
            }
            "--sphere-detail" => {
                let v = value("--sphere-detail")?;
                options.sphere_detail = v
                    .parse()
                    .map_err(|_| format!("--sphere-detail: '{v}' is not a count"))?;
                if options.sphere_detail > 6 {
                    return Err("--sphere-detail: at most 6".into());
                }
            }
            "--out" => out = PathBuf::from(value("--out")?),
            "-h" | "--help" => {
                println!(
                    "usage: meshlight-gallery [--tile METRES] [--sphere-detail N] [--out DIR]"
                );
                return Ok(());
            }
            other => return Err(format!("unknown argument '{other}' (try --help)")),
        }
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    if out != shipped_dir() {
        for file in ["scene.toml", "gallery.mtl"] {
            std::fs::copy(shipped_dir().join(file), out.join(file))
                .map_err(|e| format!("{file}: {e}"))?;
        }
    }
    let stats = write_obj(&out, options).map_err(|e| format!("{}: {e}", out.display()))?;
    println!(
        "wrote {} ({} vertices, {} triangles)",
        out.join("gallery.obj").display(),
        stats.vertices,
        stats.triangles
    );
    Ok(())
}
