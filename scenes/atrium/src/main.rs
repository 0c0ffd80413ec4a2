//! `meshlight-atrium [--detail N]`: writes the atrium's OBJ into scenes/atrium (its scene.toml
//! and atrium.mtl are there already). `--detail` (1 to 4, default 2) multiplies the facets of
//! every column, arch and vault.

use std::process::ExitCode;

fn main() -> ExitCode {
    let mut detail = meshlight_atrium::DEFAULT_DETAIL;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match (arg.as_str(), args.next()) {
            ("--detail", Some(v)) => match v.parse::<u32>() {
                Ok(d) if (1..=4).contains(&d) => detail = d,
                _ => {
                    eprintln!("meshlight-atrium: error: --detail {v}: must be 1 to 4");
                    return ExitCode::FAILURE;
                }
            },
            _ => {
                eprintln!("meshlight-atrium: error: usage: meshlight-atrium [--detail N]");
                return ExitCode::FAILURE;
            }
        }
    }
    match meshlight_atrium::write_obj(&meshlight_atrium::shipped_dir(), detail) {
        Ok(stats) => {
            println!(
                "wrote {} ({} vertices, {} triangles)",
                meshlight_atrium::shipped_dir().join("atrium.obj").display(),
                stats.vertices,
                stats.triangles
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("meshlight-atrium: error: {e}");
            ExitCode::FAILURE
        }
    }
}
