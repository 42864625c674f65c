//! `indra tune` on the adapter the tests run on: it times each option, saves the fastest in the
//! configuration folder, and `auto` parameters then draw with what it saved (read back from the
//! passes a bench names), unless the file was made for another driver or `--tuning off`.

use std::path::Path;
use std::process::{Command, Output};

use indra::gpu::tuning::Tuning;

use crate::common::text;

/// `indra` with `args`, its configuration folder under `config`.
fn indra(config: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_indra"))
        .args(args)
        .args(["--backend", "vulkan"])
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .env("XDG_CONFIG_HOME", config)
        .output()
        .expect("the binary runs")
}

/// The poisson draw a bench of `poisson_3d` used: `compute` or `pipeline`, by its passes.
fn poisson_drawn_by(config: &Path, extra: &[&str]) -> (String, String) {
    let mut args = vec!["bench", "poisson_3d", "--size", "64x36", "--frames", "2", "--warmup", "1"];
    args.extend_from_slice(extra);
    let out = indra(config, &args);
    let said = text(&out);
    assert!(out.status.success(), "{said}");
    let by = match (said.contains("poisson/raster"), said.contains("poisson/draw")) {
        (true, false) => "compute",
        (false, true) => "pipeline",
        _ => panic!("which draw ran is not in the passes: {said}"),
    };
    (by.to_string(), said)
}

#[test]
fn tune_saves_the_fastest_option_and_auto_draws_with_it_on_this_adapter_only() {
    let config = std::env::temp_dir().join(format!("indra-tune-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&config);
    let args =
        ["tune", "--size", "64x36", "--frames", "5", "--warmup", "1", "--only", "poisson", "--only", "star_glow"];
    let out = indra(&config, &args);
    assert!(out.status.success(), "{}", text(&out));
    let folder = config.join("indra/tuning");
    let files: Vec<_> = std::fs::read_dir(&folder).unwrap().flatten().map(|e| e.path()).collect();
    assert_eq!(files.len(), 1, "one file for the one adapter: {files:?}");
    let path = &files[0];
    let mut tuning = Tuning::read(path).unwrap();
    assert!(tuning.choices.iter().any(|c| c.technique == "star_glow"), "{tuning:?}");
    for choice in &tuning.choices {
        let fastest = choice.figures.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        assert_eq!(choice.chosen, fastest.0, "the fastest option is chosen: {choice:?}");
        assert!(choice.figures.iter().all(|f| f.1.is_finite() && f.1 > 0.0), "{choice:?}");
    }
    let Some(poisson) = tuning.choices.iter().position(|c| c.technique == "poisson") else {
        // Without 64-bit atomics there is only the pipeline, and nothing to choose.
        assert!(text(&out).contains("pipeline only"), "{}", text(&out));
        return;
    };
    // `auto` (poisson_3d's rasterizer) draws with the saved choice, and with the other when the
    // file says so.
    let chosen = tuning.choices[poisson].chosen.clone();
    let (by, said) = poisson_drawn_by(&config, &[]);
    assert_eq!(by, chosen, "{said}");
    assert!(said.contains(&format!("poisson.rasterizer {chosen}")), "the bench says what auto took: {said}");
    let other = if chosen == "compute" { "pipeline" } else { "compute" };
    tuning.choices[poisson].chosen = other.into();
    tuning.save(path).unwrap();
    assert_eq!(poisson_drawn_by(&config, &[]).0, other);
    // `--tuning off` and a file made for another driver take the built-in default: compute.
    assert_eq!(poisson_drawn_by(&config, &["--tuning", "off"]).0, "compute");
    tuning.key.as_mut().unwrap().driver.push_str(" (older)");
    tuning.save(path).unwrap();
    let (by, said) = poisson_drawn_by(&config, &[]);
    assert_eq!(by, "compute");
    assert!(said.contains("run `indra tune` again"), "{said}");
    // The same file named on the command line is checked as strictly.
    let (by, _) = poisson_drawn_by(&config, &["--tuning", path.to_str().unwrap()]);
    assert_eq!(by, "compute");
    std::fs::remove_dir_all(&config).unwrap();
}

#[test]
fn tune_refuses_what_it_cannot_measure_in_one_sentence() {
    let config = std::env::temp_dir().join(format!("indra-tune-bad-{}", std::process::id()));
    let out = indra(&config, &["tune", "--only", "kleinian"]);
    assert!(!out.status.success());
    assert!(text(&out).contains("nothing of 'kleinian' is tuned"), "{}", text(&out));
    let out = indra(&config, &["tune", "--frames", "0"]);
    assert!(!out.status.success());
    assert!(!config.exists(), "nothing saved");
}
