//! glTF reading under arbitrary bytes: the input is a `.glb` (or `.gltf` JSON) served as
//! `x.glb`, any other file it names (buffers, images) as empty. Loading must return a scene or
//! an error, never panic or abort. Seed it with `scenes/blender-stripes/room.glb` and
//! `tests/data/blender-room.glb`.
#![no_main]

use std::io;
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use meshlight::scene::{Scene, Source};

struct Glb<'a>(&'a [u8]);

impl Source for Glb<'_> {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        if path == Path::new("x.glb") {
            Ok(self.0.to_vec())
        } else {
            Err(io::Error::new(io::ErrorKind::NotFound, "only x.glb"))
        }
    }
}

fuzz_target!(|data: &[u8]| {
    if let Ok(scene) = Scene::load_from(&Glb(data), "x.glb") {
        assert!(!scene.triangles().is_empty());
        assert!(scene.triangles().iter().all(|t| t.area > 0.0 && t.normal.is_finite()));
        assert!(scene.camera().problem().is_none());
        assert!(scene.bounds().diagonal().is_finite());
    }
});
