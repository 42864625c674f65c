//! Renders past one machine, through the real command line: `indra bake` and
//! `render --checkpoints` give the bytes of one render whatever chunk a frame falls in (a chunk
//! killed and run again too); manifests and `indra assemble` check the frames and make the
//! video; a changed scene, a damaged checkpoint, a missing or doubled frame is one sentence. And
//! the farm jobs of `farm/` run on their real engines: PyPI's openjd-cli (`openjd check`, then
//! `openjd run … --run-dependencies`) and a single-node Slurm from Debian, started here as plain
//! processes (`sbatch --wait`).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::common::{indra, text};

/// Frames of the farm runs here: 6 chunks of 10 at 96×54 (the 600 frames of a million
/// particles take hours on lavapipe; docs/farm.md has those figures from the H200).
const FRAMES: &str = "0-59";
const PER_TASK: &str = "10";
const SIZE: &str = "96x54";

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-farm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `cloth_1024.ron` at 64² particles (as the seek test runs it): the same XPBD and wind path.
fn cloth_scene(dir: &Path) -> PathBuf {
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cloth_1024.ron")).unwrap();
    let small = source
        .replace("\"resolution\": 1024", "\"resolution\": 64")
        .replace("\"rest_length\": 0.005", "\"rest_length\": 0.08")
        .replace("\"mass\": 0.001", "\"mass\": 0.256");
    assert_ne!(small, source, "cloth_1024.ron changed: update the replacements");
    let path = dir.join("cloth_farm.ron");
    std::fs::write(&path, small).unwrap();
    path
}

fn run_ok(args: &[&str]) -> String {
    let o = indra(args);
    assert!(o.status.success(), "indra {args:?}: {}", text(&o));
    text(&o)
}

fn pngs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    files.sort();
    files
}

/// The frames of one render of `scene`, frames 0–`last`, into `dir`.
fn one_render(scene: &str, last: u64, dir: &Path) -> Vec<(String, Vec<u8>)> {
    let frames = format!("0-{last}");
    run_ok(&["render", scene, "--frames", &frames, "--size", SIZE, "--out", dir.to_str().unwrap()]);
    pngs(dir)
}

#[test]
fn chunks_from_checkpoints_are_the_bytes_of_one_render_and_assemble_checks_them() {
    let dir = temp_dir("chunks");
    let scene = cloth_scene(&dir);
    let scene = scene.to_str().unwrap();
    let (checkpoints, chunks) = (dir.join("checkpoints"), dir.join("chunks"));
    let (ck, out) = (checkpoints.to_str().unwrap(), chunks.to_str().unwrap());
    let said = run_ok(&["bake", scene, "--frames", "0-59", "--every", "20", "--size", SIZE, "--out", ck]);
    assert!(said.contains("wrote 3 checkpoint(s) of frames 0–40"), "{said}");
    // The last chunk first, and a chunk that starts between checkpoints.
    for (range, from) in [("40-59", 40), ("0-19", 0), ("25-39", 20), ("20-24", 20)] {
        let said = run_ok(&["render", scene, "--frames", range, "--size", SIZE, "--checkpoints", ck, "--out", out]);
        let name = format!("cloth_farm_{from:06}.ckpt");
        assert!(said.contains(&format!("{name} (frame {from})")), "{range} starts from {name}: {said}");
    }
    let whole = one_render(scene, 59, &dir.join("whole"));
    assert_eq!(pngs(&chunks), whole, "the chunks differ from one render");
    assert!(whole[0].1 != whole[59].1, "the cloth did not move: the comparison proves nothing");

    // A chunk killed mid-way (SIGKILL once its first frames are written) leaves frames but no
    // manifest, and a frame cut short; run again alone, it gives the same bytes.
    std::fs::remove_file(chunks.join("cloth_farm_00020-00024.sha256")).unwrap();
    std::fs::remove_file(chunks.join("cloth_farm_00025-00039.sha256")).unwrap();
    for f in 20..40 {
        std::fs::remove_file(chunks.join(format!("cloth_farm_{f:05}.png"))).unwrap();
    }
    let mut chunk = Command::new(indra_binary())
        .args(["--backend", "vulkan", "render", scene, "--frames", "20-39", "--size", SIZE, "--checkpoints", ck])
        .args(["--out", out])
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while !chunks.join("cloth_farm_00022.png").exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    chunk.kill().unwrap();
    assert!(!chunk.wait().unwrap().success(), "the chunk finished before it was killed");
    std::fs::write(chunks.join("cloth_farm_00022.png"), b"cut short").unwrap();
    let said = text(&indra(&["assemble", out, "--video", dir.join("v.mov").to_str().unwrap()]));
    assert!(said.contains("frame(s) [20, 21, 22, 23, 24, 25, 26, 27, 28, 29] are in no manifest"), "{said}");
    run_ok(&["render", scene, "--chunk", "20-39", "--size", SIZE, "--checkpoints", ck, "--out", out]);
    assert_eq!(pngs(&chunks), whole, "the chunk run again differs");

    let video = dir.join("cloth.mov");
    let said = run_ok(&["assemble", out, "--video", video.to_str().unwrap(), "--fps", "60"]);
    assert!(said.contains("checked 60 frame(s), 0–59"), "{said}");
    assert_eq!(video_frames(&video), 60);

    // A frame changed after its manifest, and two chunks that overlap.
    std::fs::write(chunks.join("cloth_farm_00030.png"), &whole[31].1).unwrap();
    let said = text(&indra(&["assemble", out, "--video", video.to_str().unwrap()]));
    assert!(said.contains("cloth_farm_00030.png is not the frame") && said.contains("changed or cut short"), "{said}");
    std::fs::write(chunks.join("cloth_farm_00030.png"), &whole[30].1).unwrap();
    run_ok(&["render", scene, "--frames", "38-41", "--size", SIZE, "--checkpoints", ck, "--out", out]);
    let said = text(&indra(&["assemble", out, "--video", video.to_str().unwrap()]));
    assert!(said.contains("is in") && said.contains("two chunks overlap"), "{said}");
}

#[test]
fn a_checkpoint_of_another_scene_or_a_damaged_one_is_refused_in_one_sentence() {
    let dir = temp_dir("refused");
    let scene = cloth_scene(&dir);
    let scene = scene.to_str().unwrap();
    let ck = dir.join("checkpoints");
    let ck = ck.to_str().unwrap();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    run_ok(&["bake", scene, "--frames", "10-10", "--every", "10", "--size", SIZE, "--out", ck]);
    let render = |extra: &[&str]| {
        let mut args = vec!["render", scene, "--frames", "12-13", "--size", SIZE, "--checkpoints", ck, "--out", out];
        args.extend_from_slice(extra);
        indra(&args)
    };
    let o = render(&["--set", "cloth.wind_strength=0.01"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("was made from another version of 'GPU cloth 1024² (XPBD, wind)'"), "{}", text(&o));
    let o = render(&["--seed", "9"]);
    assert!(!o.status.success() && text(&o).contains("another --dt or --seed"), "{}", text(&o));

    // Made on another GPU: refused, unless the render accepts closeness.
    let file = dir.join("checkpoints/cloth_farm_000010.ckpt");
    let baked = std::fs::read(&file).unwrap();
    let mut checkpoint = indra::checkpoint::Checkpoint::read(&file).unwrap();
    let made_on = checkpoint.header.adapter.clone();
    checkpoint.header.adapter = "NVIDIA H200 (Vulkan)".into();
    checkpoint.write(&file).unwrap();
    let o = render(&[]);
    assert!(!o.status.success());
    let said = text(&o);
    assert!(said.contains("was made on NVIDIA H200 (Vulkan)") && said.contains(&made_on), "{said}");
    assert!(said.contains("pass --accept-other-adapter to use it anyway"), "{said}");
    let said = text(&render(&["--accept-other-adapter"]));
    assert!(said.contains("starting from") && said.contains("wrote 2 frame(s)"), "{said}");

    let mut bytes = baked;
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x40;
    std::fs::write(&file, &bytes).unwrap();
    let o = render(&[]);
    assert!(!o.status.success());
    assert!(text(&o).contains("is not a usable checkpoint: its checksum does not match"), "{}", text(&o));
    std::fs::write(&file, b"not a checkpoint at all, but long enough to be read as one, surely").unwrap();
    let o = render(&[]);
    assert!(text(&o).contains("it does not start as an indra checkpoint does"), "{}", text(&o));
    // No checkpoint at or before the chunk: it simulates from 0, as without.
    std::fs::remove_file(&file).unwrap();
    let said = text(&render(&[]));
    assert!(said.contains("no checkpoint of 'GPU cloth 1024² (XPBD, wind)' at or before frame 12"), "{said}");
}

/// Frames in a video, by ffprobe.
fn video_frames(video: &Path) -> u64 {
    let o = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries", "stream=nb_read_frames"])
        .args(["-of", "csv=p=0"])
        .arg(video)
        .output()
        .expect("ffprobe runs");
    String::from_utf8_lossy(&o.stdout).trim().parse().unwrap_or_else(|_| panic!("ffprobe: {}", text(&o)))
}

/// A farm engine's command, from the variable `tools/setup-farm-peer` prints; `None` skips the
/// test (not on CI).
fn engine(variable: &str) -> Option<PathBuf> {
    match std::env::var_os(variable) {
        Some(path) => Some(PathBuf::from(path)),
        None if std::env::var_os("CI").is_some() => panic!("{variable} is not set: run tools/setup-farm-peer"),
        None => {
            eprintln!("skipped: {variable} is not set (eval \"$(bash tools/setup-farm-peer)\")");
            None
        }
    }
}

fn indra_binary() -> &'static str {
    env!("CARGO_BIN_EXE_indra")
}

#[test]
fn the_openjd_template_renders_the_bytes_of_one_render() {
    let Some(openjd) = engine("INDRA_OPENJD") else { return };
    let dir = temp_dir("openjd");
    let scene = cloth_scene(&dir);
    let template = concat!(env!("CARGO_MANIFEST_DIR"), "/farm/openjd/render.yaml");
    let check = Command::new(&openjd).args(["check", template]).output().unwrap();
    assert!(check.status.success(), "openjd check: {}", text(&check));
    let out = dir.join("job");
    let params = [
        format!("Indra={}", indra_binary()),
        format!("Scene={}", scene.display()),
        format!("Frames={FRAMES}"),
        format!("FramesPerTask={PER_TASK}"),
        format!("Size={SIZE}"),
        format!("OutputDir={}", out.display()),
    ];
    let mut run = Command::new(&openjd);
    run.args(["run", template, "--step", "Assemble", "--run-dependencies"]);
    for p in &params {
        run.args(["-p", p]);
    }
    // The indra processes find the bundled scenes and shaders beside the test build.
    let o = run.env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR")).stdin(Stdio::null()).output().unwrap();
    let log = text(&o);
    assert!(o.status.success(), "openjd run: {log}");
    assert_eq!(log.matches("starting from ").count(), 6, "six chunks, each from its checkpoint: {log}");
    let whole = one_render(scene.to_str().unwrap(), 59, &dir.join("whole"));
    assert_eq!(pngs(&out.join("frames")), whole, "the OpenJD job's frames differ from one render");
    assert_eq!(video_frames(&out.join("render.mov")), 60);
}

#[cfg(target_os = "linux")]
#[test]
fn the_slurm_array_job_renders_the_bytes_of_one_render() {
    let Some(sbatch) = engine("INDRA_SBATCH") else { return };
    let dir = temp_dir("slurm");
    let cluster = crate::slurm::Cluster::start(&dir.join("cluster"), &sbatch);
    let scene = cloth_scene(&dir);
    let out = dir.join("job");
    let submit = concat!(env!("CARGO_MANIFEST_DIR"), "/farm/slurm/submit.sh");
    let o = cluster
        .command("bash")
        .arg(submit)
        .args([scene.to_str().unwrap(), out.to_str().unwrap()])
        .args(["--frames", FRAMES, "--per-task", PER_TASK, "--size", SIZE, "--indra", indra_binary(), "--wait"])
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let logs = cluster.job_logs(&out.join("logs"));
    assert!(o.status.success(), "sbatch --wait: {}\n{logs}", text(&o));
    assert!(text(&o).contains("(6 tasks)"), "{}", text(&o));
    assert_eq!(logs.matches("starting from ").count(), 6, "six chunks, each from its checkpoint: {logs}");
    let whole = one_render(scene.to_str().unwrap(), 59, &dir.join("whole"));
    assert_eq!(pngs(&out.join("frames")), whole, "the Slurm job's frames differ from one render");
    assert_eq!(video_frames(&out.join("render.mov")), 60);
}
