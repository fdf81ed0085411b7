//! `e` in a lesson writes the current frame as a PNG.

use springlab::scene;
use springlab::simulation::Simulation;
use springlab::tui::export::{EXPORT_SIZE, export_png};

#[test]
fn export_writes_a_png_of_the_scene() {
    let dir = std::env::temp_dir().join(format!("springlab-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut sim = Simulation::new(scene::load("cloth-sphere", &[]).expect("scene"));
    sim.run(50, |_| {});
    let path = dir.join("frame.png");
    let written = export_png(&sim, 0.3, 0.4, &path).expect("export");
    assert_eq!(written, path);
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&path).expect("png"),
    ));
    let reader = decoder.read_info().expect("a PNG");
    let info = reader.info();
    assert_eq!((info.width, info.height), EXPORT_SIZE);
    // An unwritable path gives a message, not a panic.
    let err = export_png(&sim, 0.0, 0.0, &dir.join("no/such/dir/x.png")).expect_err("unwritable");
    assert!(err.starts_with("cannot write"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
