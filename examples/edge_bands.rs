//! Prints the error along a box-shaped room's ceiling–wall edges that `docs/accuracy.md`
//! ("Local error: the worst blocks") quotes: the scene is solved and rendered at the defaults,
//! each pixel's centre ray finds the point it sees, and pixels on the ceiling or a wall are
//! grouped by their distance to the nearest ceiling–wall edge; each band's mean is divided by
//! the reference's over the same pixels.
//!
//! `cargo run --release --example edge_bands -- SCENE.toml REFERENCE.exr [GATHER_RAYS]` (the
//! reference at the scene's image size, e.g. from `meshlight render SCENE.toml --method
//! pathtrace`; gather rays as `render --gather-rays`, default the library's). The room is the
//! scene's bounding box: ceiling at its top, walls at its four sides.

use meshlight::visibility::Ray;
use meshlight::{Backend, Control, Image, Options, RenderOptions, Scene};

/// Band edges, metres from the ceiling–wall edge.
const BANDS: [f32; 6] = [0.0, 0.02, 0.05, 0.1, 0.2, 0.4];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (scene, reference, gather_rays) = match args.as_slice() {
        [s, r] => (s, r, RenderOptions::default().gather_rays),
        [s, r, g] => (s, r, g.parse()?),
        _ => return Err("usage: edge_bands SCENE.toml REFERENCE.exr [GATHER_RAYS]".into()),
    };
    let scene = Scene::load(scene)?;
    let reference = Image::read_exr(std::path::Path::new(reference))?;
    let vis = Backend::default_backend().build(&scene)?;
    let solution = meshlight::solve(&scene, vis.as_ref(), &Options::default(), &mut |_| {
        Control::Continue
    })?;
    let (image, _) = meshlight::render(
        &scene,
        &solution,
        vis.as_ref(),
        &RenderOptions {
            gather_rays,
            ..RenderOptions::default()
        },
        &mut |_| Control::Continue,
    )?;
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err("the reference is not at the scene's image size".into());
    }
    let rays: Vec<Ray> = scene.camera().pixel_centres().collect();
    let mut hits = vec![None; rays.len()];
    vis.intersect(&rays, &mut hits)?;
    let (lo, hi) = (scene.bounds().min, scene.bounds().max);
    // Per surface kind (ceiling, wall) and band: our sum, the reference's, pixels.
    let mut sums = [[(0.0f64, 0.0f64, 0usize); BANDS.len() - 1]; 2];
    for (p, hit) in hits.iter().enumerate() {
        let Some(hit) = hit else { continue };
        let q = rays[p].origin + hit.t * rays[p].dir;
        let to_wall = (q.x - lo.x).min(hi.x - q.x).min(q.z - lo.z).min(hi.z - q.z);
        let to_ceiling = hi.y - q.y;
        let (d, kind) = if to_ceiling < 1e-3 {
            (to_wall, 0)
        } else if to_wall < 1e-3 {
            (to_ceiling, 1)
        } else {
            continue;
        };
        if let Some(b) = BANDS.windows(2).position(|e| (e[0]..e[1]).contains(&d)) {
            let s = &mut sums[kind][b];
            s.0 += f64::from(image.pixels[p].element_sum());
            s.1 += f64::from(reference.pixels[p].element_sum());
            s.2 += 1;
        }
    }
    for (kind, name) in ["ceiling", "wall"].iter().enumerate() {
        for (b, &(ours, theirs, n)) in sums[kind].iter().enumerate() {
            if n > 0 {
                println!(
                    "{name} {:.2}-{:.2} m from the edge: {:+.1}% ({n} pixels)",
                    BANDS[b],
                    BANDS[b + 1],
                    100.0 * (ours / theirs - 1.0)
                );
            }
        }
    }
    Ok(())
}
