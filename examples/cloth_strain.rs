//! Runs a hanging cloth headless and prints the top-row strain over time — the stiffness measure
//! of issue 5 (goal: under 10% for a 1024² cloth with the XPBD solver).
//!
//! `cargo run --release --example cloth_strain -- [resolution solver substeps seconds]`
//! (defaults: 1024 XPBD 16 10; the cloth is 5.12 m wide, 1 g per particle, 60 steps/s, no sphere).

use indra::assets::Assets;
use indra::gpu::{Gpu, GpuOptions};
use indra::params::ParamSet;
use indra::scene::parse_value_override;
use indra::techniques::Technique;
use indra::techniques::cloth::runner::{runner, top_row_strain};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.to_string());
    let res: usize = arg(0, "1024").parse().expect("resolution");
    let (solver, substeps, seconds) = (arg(1, "XPBD"), arg(2, "16"), arg(3, "10").parse::<u32>().expect("seconds"));
    let rest = 5.12 / res as f32;
    let mut params = ParamSet::new(indra::techniques::cloth::Settings::decls());
    let settings = [
        ("resolution", res.to_string()),
        ("solver", solver.clone()),
        ("substeps", substeps.clone()),
        ("rest_length", rest.to_string()),
        ("mass", "0.001".into()),
        ("damping", "0.5".into()),
        ("stiffness", "1000".into()),
        ("sphere", "false".into()),
    ];
    for (name, value) in &settings {
        let i = params.index(name).expect("declared");
        params.set_at(i, parse_value_override(value, &params.decls()[i]).expect("valid"));
    }
    params.snap();
    let gpu = Gpu::headless(&GpuOptions::default()).expect("a GPU");
    println!("{} — {res}² {solver}, {substeps} substeps, 60 steps/s", gpu.adapter_label());
    let assets = Assets::new(Some(env!("CARGO_MANIFEST_DIR").into()));
    let mut runner = runner(gpu, &assets, params, 1.0 / 60.0).expect("cloth builds");
    for second in 1..=seconds {
        runner.run(60);
        let p = runner.node.positions();
        let finite = p.iter().all(|q| q.iter().all(|c| c.is_finite()));
        let resets = runner.node.take_messages().len();
        println!(
            "t = {second:>3} s: top-row strain {:.2}%  finite {finite}  resets {resets}",
            top_row_strain(&p, res, rest) * 100.0
        );
    }
}
