//! `meshlight-gallery [--tile T] [--sphere-detail N] [--rooms NXxNZ] [--out DIR]`: writes the
//! gallery's OBJ (into scenes/gallery by default; elsewhere with its scene.toml and gallery.mtl
//! beside it). A gallery of another size than the shipped 2x2 rooms needs a folder of its own
//! and gets a scene.toml written for it (two point lights per room).

use std::path::PathBuf;
use std::process::ExitCode;

use meshlight_gallery::{shipped_dir, write_scene, GalleryOptions};

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
            "--rooms" => {
                let v = value("--rooms")?;
                let parse = |x: &str| {
                    x.trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&n| (1..=64).contains(&n))
                };
                options.rooms = match v.split_once(['x', 'X']) {
                    Some((a, b)) => match (parse(a), parse(b)) {
                        (Some(a), Some(b)) => [a, b],
                        _ => {
                            return Err(format!(
                                "--rooms {v}: expected NXxNZ, each 1 to 64 (e.g. 4x4)"
                            ))
                        }
                    },
                    None => return Err(format!("--rooms {v}: expected NXxNZ, e.g. 4x4")),
                };
            }
            "--out" => out = PathBuf::from(value("--out")?),
            "--skylights" => options.skylights = true,
            "-h" | "--help" => {
                println!(
                    "usage: meshlight-gallery [--tile METRES] [--sphere-detail N] [--rooms NXxNZ] [--skylights] [--out DIR]"
                );
                return Ok(());
            }
            other => return Err(format!("unknown argument '{other}' (try --help)")),
        }
    }
    if options.rooms != GalleryOptions::default().rooms && out == shipped_dir() {
        return Err(format!(
            "--rooms {}x{}: a gallery of another size needs a folder of its own (--out DIR); \
             the shipped one stays 2x2",
            options.rooms[0], options.rooms[1]
        ));
    }
    let stats = write_scene(&out, options).map_err(|e| format!("{}: {e}", out.display()))?;
    println!(
        "wrote {} ({} vertices, {} triangles)",
        out.join(meshlight_gallery::obj_name(options)).display(),
        stats.vertices,
        stats.triangles
    );
    Ok(())
}
