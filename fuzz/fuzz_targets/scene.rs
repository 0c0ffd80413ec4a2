//! Scene parsing under arbitrary bytes: the input is three files separated by NUL bytes
//! (scene TOML, OBJ, MTL); whatever path the scene names is served from the part its
//! extension picks. Loading must return a scene or an error, never panic or abort.
#![no_main]

use std::io;
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use meshlight::scene::{Scene, Source};

struct Parts<'a>([&'a [u8]; 3]);

impl Source for Parts<'_> {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        let part = match path.extension().and_then(|e| e.to_str()) {
            Some("obj") => 1,
            Some("mtl") => 2,
            _ => 0,
        };
        Ok(self.0[part].to_vec())
    }
}

fuzz_target!(|data: &[u8]| {
    let mut parts = data.splitn(3, |&b| b == 0);
    let files = Parts([parts.next().unwrap_or(&[]), parts.next().unwrap_or(&[]), parts.next().unwrap_or(&[])]);
    if let Ok(scene) = Scene::load_from(&files, "scene.toml") {
        // What loaded must be usable: finite geometry, at least one triangle, valid camera.
        assert!(!scene.triangles().is_empty());
        assert!(scene.triangles().iter().all(|t| t.area > 0.0 && t.normal.is_finite()));
        assert!(scene.camera().problem().is_none());
        assert!(scene.bounds().diagonal().is_finite());
    }
});
