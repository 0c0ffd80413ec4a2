//! Compiles the C shim against whichever Embree headers are installed (4 preferred, then 3) and
//! links the matching library. Debian 12's `libembree-dev` is Embree 3.13.5 (<embree3/rtcore.h>,
//! -lembree3, no pkg-config file); Debian 13's is Embree 4 (<embree4/rtcore.h>, -lembree4).
//!
//! Environment: `EMBREE_INCLUDE_DIR` and `EMBREE_LIB_DIR` add a search place for headers and
//! library (a local Embree build); `MESHLIGHT_EMBREE_MAJOR=3|4` forces a version.

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=shim.c");
    println!("cargo:rerun-if-changed=shim.h");
    for var in [
        "EMBREE_INCLUDE_DIR",
        "EMBREE_LIB_DIR",
        "MESHLIGHT_EMBREE_MAJOR",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }

    let mut include_dirs: Vec<PathBuf> = Vec::new();
    if let Some(dir) = env::var_os("EMBREE_INCLUDE_DIR") {
        include_dirs.push(dir.into());
    }
    include_dirs.extend(["/usr/include", "/usr/local/include"].map(PathBuf::from));

    let forced = env::var("MESHLIGHT_EMBREE_MAJOR").ok();
    let majors: Vec<u32> = match forced.as_deref() {
        Some("3") => vec![3],
        Some("4") => vec![4],
        _ => vec![4, 3],
    };
    let found = majors.iter().find_map(|&major| {
        include_dirs.iter().find_map(|dir| {
            let header = dir.join(format!("embree{major}")).join("rtcore.h");
            header.is_file().then(|| (major, dir.clone(), header))
        })
    });
    let Some((major, include_dir, header)) = found else {
        panic!(
            "meshlight-embree-sys: no Embree headers found (looked for embree4/rtcore.h and \
             embree3/rtcore.h in {:?}). Install them with `apt-get install libembree-dev`, set \
             EMBREE_INCLUDE_DIR, or build meshlight with `--no-default-features` for the pure-Rust \
             obvhs backend alone.",
            include_dirs
        );
    };

    cc::Build::new()
        .file("shim.c")
        .include(&include_dir)
        .define("ML_EMBREE_MAJOR", major.to_string().as_str())
        .flag_if_supported("-std=c11")
        .opt_level(2)
        .warnings(true)
        .compile("meshlight_embree_shim");

    if let Some(dir) = env::var_os("EMBREE_LIB_DIR") {
        println!(
            "cargo:rustc-link-search=native={}",
            PathBuf::from(dir).display()
        );
    }
    println!("cargo:rustc-link-lib=dylib=embree{major}");
    // The library side reports which headers it was built against (`meshlight bench-vis` prints it).
    println!(
        "cargo:rustc-env=MESHLIGHT_EMBREE_HEADERS={}",
        header.display()
    );
    println!("cargo:rustc-env=MESHLIGHT_EMBREE_MAJOR={major}");
    // Say which Embree was picked (cargo shows this once, when the shim is compiled).
    println!(
        "cargo:warning=compiling the C shim against Embree {major} ({})",
        header.display()
    );
}
