//! Drawing one 640×480 frame of a cloth-spheres-like and a jelly-bowl-like scene.
//!
//! `cargo bench -p springlab-benches --bench render`. Frames per second = 1 / the median time. The scenes are built
//! from the lattice builders and collider constructors (`tests/common/render_scenes.rs`) and
//! simulated for a while first, so the cloth is draped over the spheres and the jelly is in the
//! bowl; only the drawing is timed (not the PNG encoding, which runs on its own thread).

#[path = "../tests/common/render_scenes.rs"]
mod render_scenes;

use criterion::{Criterion, criterion_group, criterion_main};
use springlab::render::{Colouring, Projection, Renderer, Style};
use springlab::simulation::Simulation;

fn bench_frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("render/640x480");
    let cases = [
        (
            "cloth-spheres",
            render_scenes::cloth_spheres(),
            8000,
            Style::default(),
        ),
        (
            "jelly-bowl",
            render_scenes::jelly_bowl(),
            2000,
            Style::default(),
        ),
        (
            "jelly-bowl-springs",
            render_scenes::jelly_bowl(),
            2000,
            Style {
                jelly_surface: false,
                ..Style::default()
            },
        ),
        (
            "jelly-bowl-strain",
            render_scenes::jelly_bowl(),
            2000,
            Style {
                colouring: Colouring::ByStrain { max_strain: 0.1 },
                ..Style::default()
            },
        ),
    ];
    for (name, scene, steps, style) in cases {
        let renderer =
            Renderer::new(&scene, 640, 480, Projection::default(), style).expect("valid size");
        let mut sim = Simulation::new(scene);
        sim.run(steps, |_| {});
        assert!(sim.diverged.is_none(), "{name} diverged");
        group.bench_function(name, |b| b.iter(|| renderer.draw_simulation(&sim)));
    }
    group.finish();
}

criterion_group!(benches, bench_frames);
criterion_main!(benches);
