//! `indra render --video` end to end: ffmpeg writes the frames the PNG path writes, at the
//! scene's frame rate, and a missing ffmpeg is one sentence. Needs `ffmpeg` and `ffprobe`
//! (tools/setup-system installs them).

use crate::common;

use std::path::{Path, PathBuf};

use crate::common::text;
use std::process::{Command, Output};

fn indra(args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_indra"));
    command.args(args).args(["--backend", "vulkan"]).env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"));
    command
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-video-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs an ffmpeg tool; its absence is a set-up error worth saying plainly.
fn tool(name: &str, args: &[&str]) -> Output {
    let o = Command::new(name)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{name} is needed for this test ({e}): run tools/setup-system test"));
    assert!(o.status.success(), "{name} {args:?}: {}", text(&o));
    o
}

/// `ffprobe`'s stream fields as `key=value` pairs.
fn probe(path: &Path) -> std::collections::HashMap<String, String> {
    let o = tool(
        "ffprobe",
        &[
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_read_frames,width,height,r_frame_rate,codec_name",
            "-of",
            "default=nw=1",
            path.to_str().unwrap(),
        ],
    );
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| l.split_once('=').map(|(k, v)| (k.to_string(), v.to_string())))
        .collect()
}

/// The first frame of a video as RGBA bytes, converted back with the BT.709 matrix it was
/// written with.
fn first_frame(path: &Path) -> Vec<u8> {
    tool(
        "ffmpeg",
        &[
            "-v",
            "error",
            "-i",
            path.to_str().unwrap(),
            "-frames:v",
            "1",
            "-vf",
            "scale=in_color_matrix=bt709:in_range=tv",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgba",
            "-",
        ],
    )
    .stdout
}

/// Mean absolute difference per colour channel (alpha left out), in 8-bit levels.
fn mean_difference(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    let pairs = a.chunks(4).zip(b.chunks(4)).flat_map(|(p, q)| (0..3).map(move |c| p[c].abs_diff(q[c])));
    pairs.map(f64::from).sum::<f64>() / (a.len() / 4 * 3) as f64
}

/// Renders `scene` from frame 5 as a video of `frames` frames and as PNGs of frames 5 and 6.
fn video_and_pngs(dir: &Path, scene: &str, frames: &str) -> (PathBuf, Vec<u8>, Vec<u8>) {
    let video = dir.join(format!("clip/{scene}.mp4"));
    let base = ["render", scene, "--size", "96x64", "--start", "5"];
    let o = indra(&base).args(["--frames", frames, "--video", video.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let o = indra(&base).args(["--frames", "2", "--out", dir.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let png = |n: u32| image::open(dir.join(format!("{scene}_0000{n}.png"))).unwrap().to_rgba8().into_raw();
    (video, png(5), png(6))
}

#[test]
fn a_video_holds_every_frame_at_the_scene_rate_in_bt709() {
    let dir = temp_dir("mp4");
    let (video, png, _) = video_and_pngs(&dir, "cloth", "30");
    let info = probe(&video);
    assert_eq!(info["codec_name"], "h264");
    assert_eq!((info["width"].as_str(), info["height"].as_str()), ("96", "64"));
    assert_eq!(info["nb_read_frames"], "30");
    assert_eq!(info["r_frame_rate"], "50/1", "the cloth scene steps 0.02 s: 50 fps");
    // H.264 at CRF 18 with 4:2:0 chroma: close, not equal (1.8 levels here). Written with the
    // BT.601 matrix it would be 3.3 levels off when read as tagged.
    let mean = mean_difference(&png, &first_frame(&video));
    assert!(mean < 2.5, "mean difference {mean:.2} levels between the PNG and the video's first frame");
}

#[test]
fn a_video_starts_at_the_frame_the_png_path_starts_at() {
    // StarGlow's streaks turn fast: neighbouring frames differ by ~20 levels, the codec by ~4.
    let dir = temp_dir("frame");
    let (video, frame5, frame6) = video_and_pngs(&dir, "star_glow", "2");
    let first = first_frame(&video);
    let (same, next) = (mean_difference(&frame5, &first), mean_difference(&frame6, &first));
    assert!(same < next / 3.0, "the video's first frame is {same:.2} from frame 5 and {next:.2} from frame 6");
}

#[test]
fn odd_sizes_and_every_container_encode() {
    let dir = temp_dir("containers");
    for (file, codec) in [("a.mov", "prores"), ("a.webm", "vp9"), ("a.mkv", "h264")] {
        let path = dir.join(file);
        let o = indra(&["render", "star_glow", "--size", "33x17", "--frames", "3", "--video", path.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{file}: {}", text(&o));
        assert!(text(&o).contains("34x18"), "the padding is said: {}", text(&o));
        let info = probe(&path);
        assert_eq!(info["codec_name"], codec, "{file}");
        assert_eq!(info["nb_read_frames"], "3", "{file}");
        assert_eq!((info["width"].as_str(), info["height"].as_str()), ("34", "18"), "{file}");
    }
}

#[test]
fn a_missing_ffmpeg_or_encoder_is_one_sentence_before_any_frame() {
    let dir = temp_dir("missing");
    let video = dir.join("a.mp4");
    let o = indra(&["render", "kleinian", "--video", video.to_str().unwrap()])
        .env("PATH", dir.to_str().unwrap())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("ffmpeg was not found") && text(&o).contains("apt-get install ffmpeg"), "{}", text(&o));
    assert!(!text(&o).contains("rendering"), "it fails before the GPU starts: {}", text(&o));

    for (args, said) in
        [(vec!["--codec", "no-such-encoder"], "no encoder 'no-such-encoder'"), (vec!["--quality", "99"], "past 51")]
    {
        let o = indra(&["render", "kleinian", "--video", video.to_str().unwrap()]).args(&args).output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(text(&o).contains(said), "{}", text(&o));
    }
    let o = indra(&["render", "kleinian", "--video", dir.join("a.gif").to_str().unwrap()]).output().unwrap();
    assert!(text(&o).contains(".mp4, .mov, .webm or .mkv"), "{}", text(&o));
    assert!(!video.exists(), "no file is left behind by a refused render");
}

/// A float texture of one colour, as a node's output would be.
fn solid(gpu: &indra::gpu::Gpu, size: (u32, u32), level: f32) -> wgpu::Texture {
    common::float_texture(gpu, size, &vec![[level, level, level, 1.0]; (size.0 * size.1) as usize]).texture
}

fn live_settings(path: &Path, size: (u32, u32)) -> indra::offscreen::VideoSettings {
    indra::offscreen::VideoSettings {
        path: path.into(),
        size,
        fps: 30.0,
        codec: None,
        quality: None,
        audio: None,
        stream: false,
        pace: false,
    }
}

#[test]
fn a_live_recording_writes_each_shown_frame_for_every_step_it_advanced() {
    let gpu = common::gpu();
    let dir = temp_dir("live");
    let path = dir.join("show.mp4");
    let size = (64, 48);
    let mut recorder = indra::offscreen::LiveRecorder::start(&gpu.device, live_settings(&path, size), 4).unwrap();
    // Shown frames that advanced 1, 0, 2, 1, … steps: the video holds the sum, in show time.
    let steps = [1u32, 0, 2, 1, 3, 1, 0, 1, 1, 2];
    for (i, &n) in steps.iter().enumerate() {
        let texture = solid(&gpu, size, i as f32 / 10.0);
        let view = texture.create_view(&Default::default());
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        recorder.capture(&gpu.device, &mut encoder, &view, n, 0);
        gpu.queue.submit([encoder.finish()]);
        recorder.after_submit();
        // The show waits for its own frame, never for the recorder.
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
        recorder.poll(&gpu.device);
    }
    let report = recorder.finish(&gpu.device).unwrap();
    let total: u32 = steps.iter().sum();
    assert_eq!(report.counts.offered, u64::from(total));
    assert_eq!(report.counts.dropped(), 0, "{report}");
    assert_eq!(report.written, u64::from(total));
    let info = probe(&path);
    assert_eq!(info["nb_read_frames"], total.to_string());
    assert_eq!(info["r_frame_rate"], "30/1");
    // Each shown frame appears as often as its steps, in order (levels 0.0, 0.2, 0.2, 0.3, …).
    let decoded = tool(
        "ffmpeg",
        &[
            "-v",
            "error",
            "-i",
            path.to_str().unwrap(),
            "-vf",
            "scale=in_color_matrix=bt709:in_range=tv",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "gray",
            "-",
        ],
    )
    .stdout;
    let frame_bytes = (size.0 * size.1) as usize;
    let means: Vec<f64> = decoded
        .chunks(frame_bytes)
        .map(|f| f.iter().map(|&b| f64::from(b)).sum::<f64>() / frame_bytes as f64)
        .collect();
    let srgb = |x: f64| if x <= 0.0031308 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    let expected: Vec<f64> = steps
        .iter()
        .enumerate()
        .flat_map(|(i, &n)| std::iter::repeat_n(srgb(i as f64 / 10.0) * 255.0, n as usize))
        .collect();
    assert_eq!(means.len(), expected.len());
    for (k, (got, want)) in means.iter().zip(&expected).enumerate() {
        assert!((got - want).abs() < 3.0, "video frame {k}: mean {got:.1}, expected {want:.1}");
    }
}

#[test]
fn frames_a_busy_readback_cannot_take_are_counted_not_lost_silently() {
    let gpu = common::gpu();
    let dir = temp_dir("busy");
    let path = dir.join("show.mkv");
    let size = (32, 32);
    // Two buffers and a show that never lets the recorder poll: from the third frame on, every
    // frame finds both buffers in flight.
    let mut recorder = indra::offscreen::LiveRecorder::start(&gpu.device, live_settings(&path, size), 2).unwrap();
    let texture = solid(&gpu, size, 0.5);
    let view = texture.create_view(&Default::default());
    for _ in 0..10 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        recorder.capture(&gpu.device, &mut encoder, &view, 1, 0);
        gpu.queue.submit([encoder.finish()]);
        recorder.after_submit();
    }
    let counts = recorder.counts();
    assert_eq!((counts.offered, counts.dropped_busy), (10, 8));
    let report = recorder.finish(&gpu.device).unwrap();
    assert_eq!(report.written, 2);
    assert!(report.to_string().contains("8 frame(s) were not recorded"), "{report}");
    assert_eq!(probe(&path)["nb_read_frames"], "2");
}

/// A free loopback port (bound, then let go, for a receiver to take).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

#[test]
fn a_render_streams_over_srt_udp_and_rtmp_to_an_ffmpeg_receiver() {
    let dir = temp_dir("stream");
    let (base, pngs) = (["render", "kleinian_classic", "--size", "96x64"], dir.join("png"));
    let o = indra(&base).args(["--frames", "1", "--out", pngs.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let sent = image::open(pngs.join("kleinian_classic_00000.png")).unwrap().to_rgba8().into_raw();
    for scheme in ["srt", "udp", "rtmp"] {
        let port = free_port();
        let (listen, send) = match scheme {
            "srt" => (format!("srt://127.0.0.1:{port}?mode=listener"), format!("srt://127.0.0.1:{port}?mode=caller")),
            // ffmpeg as the RTMP server a streaming PC would run.
            "rtmp" => (format!("rtmp://127.0.0.1:{port}/live/indra"), format!("rtmp://127.0.0.1:{port}/live/indra")),
            _ => (
                format!("udp://127.0.0.1:{port}?overrun_nonfatal=1&fifo_size=100000"),
                format!("udp://127.0.0.1:{port}"),
            ),
        };
        let received = dir.join(format!("{scheme}.rgba"));
        // The receiver writes the frames as raw RGBA.
        let mut receiver = Command::new("ffmpeg");
        // A second of stream is enough to find the codec's parameters (5 s by default).
        receiver.args(["-v", "error", "-y", "-analyzeduration", "1000000"]);
        if scheme == "rtmp" {
            receiver.args(["-listen", "1", "-f", "flv"]);
        } else {
            receiver.args(["-f", "mpegts"]);
        }
        // SRT and RTMP end with the sender; UDP never does, so its receiver stops after 20.
        let count = if scheme == "udp" { "20" } else { "1000" };
        let mut receiver = receiver
            .args(["-i", &listen, "-frames:v", count, "-vf", "scale=in_color_matrix=bt709:in_range=tv"])
            .args(["-f", "rawvideo", "-pix_fmt", "rgba", received.to_str().unwrap()])
            .spawn()
            .expect("ffmpeg is needed for this test: run tools/setup-system test");
        std::thread::sleep(std::time::Duration::from_millis(700));
        // Three seconds, sent in real time.
        let o = indra(&base).args(["--frames", "180", "--stream", &send]).output().unwrap();
        assert!(o.status.success(), "{scheme}: {}", text(&o));
        let start = std::time::Instant::now();
        while receiver.try_wait().unwrap().is_none() && start.elapsed().as_secs() < 20 {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let _ = receiver.kill();
        let bytes = std::fs::read(&received).unwrap_or_default();
        let frame = 96 * 64 * 4;
        // UDP: the 20 the receiver asked for. SRT, RTMP: all but the few still in flight when
        // the sender closed.
        let arrived = bytes.len() / frame;
        let enough = if scheme == "udp" { arrived == 20 } else { arrived >= 150 };
        assert!(bytes.len().is_multiple_of(frame) && enough, "{scheme}: {arrived} frames of 96x64 arrived");
        // The static scene comes through the encoder close to the PNG of its frame.
        let diff = mean_difference(&bytes[..frame], &sent);
        assert!(diff < 6.0, "{scheme}: the first frame differs by {diff:.2} levels");
    }
    // A URL of another kind is one sentence, before any frame.
    let o = indra(&base).args(["--frames", "1", "--stream", "http://127.0.0.1:1/x"]).output().unwrap();
    assert!(!o.status.success() && text(&o).contains("srt://HOST:PORT"), "{}", text(&o));
}
