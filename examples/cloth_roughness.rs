//! Runs the `cloth_1024` scene headless and prints, every second, how wrinkled the sheet is: the
//! roughness of the whole sheet and of its top and bottom quarters (RMS deviation of a particle
//! from the mean of its four neighbours, in rest lengths; see `cloth::runner::roughness`).
//!
//! `cargo run --release --example cloth_roughness -- [resolution seconds [param=value …]]`
//! (defaults: 1024 10; the cloth stays 5.12 m wide with the scene's mass per area, so every
//! resolution shows the same sheet).

use indra::assets::Assets;
use indra::gpu::{Gpu, GpuOptions};
use indra::scene::load_scene;
use indra::techniques::cloth::runner::{roughness, runner};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let res: usize = args.first().map_or(Ok(1024), |a| a.parse()).expect("resolution");
    let seconds: u32 = args.get(1).map_or(Ok(10), |a| a.parse()).expect("seconds");
    let assets = Assets::discover();
    let mut scene = load_scene(&assets, "cloth_1024").expect("the cloth_1024 scene");
    let rest = 5.12 / res as f32;
    let mass = 0.001 * (1024.0 / res as f32).powi(2);
    let sets = [format!("cloth.resolution={res}"), format!("cloth.rest_length={rest}"), format!("cloth.mass={mass}")];
    for set in sets.iter().chain(args.iter().skip(2)) {
        scene.set_from_str(set).expect("a parameter of the scene");
    }
    let gpu = Gpu::headless(&GpuOptions::default()).expect("a GPU");
    println!(
        "{} — cloth_1024 at {res}², {}",
        gpu.adapter_label(),
        args.get(2..).map(|a| a.join(" ")).unwrap_or_default()
    );
    let steps = (1.0 / scene.dt).round() as u32;
    let mut rig = runner(gpu, &assets, scene.nodes[0].params.clone(), scene.dt).expect("cloth builds");
    for second in 1..=seconds {
        rig.run(steps);
        let p = rig.node.positions();
        let quarter = res / 4;
        println!(
            "t = {second:>2} s: roughness {:.4}  top quarter {:.4}  bottom quarter {:.4}",
            roughness(&p, res, rest, 0..res),
            roughness(&p, res, rest, 0..quarter),
            roughness(&p, res, rest, res - quarter..res)
        );
    }
}
