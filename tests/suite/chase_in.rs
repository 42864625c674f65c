//! A show chasing a desk's timecode on real ports (JACK, as the controller tests): MTC on a MIDI
//! port, and LTC (libltc's, `tests/timecode/ltcgen.c`) on an audio port. The desk — a JACK
//! client of the test's, on its own clock — runs, jumps back, drops out and stops; the show's
//! log says, every frame, where it heard the code and which frame it shows. Both clocks are the
//! machine's wall clock, so the test knows where the desk was at each of the show's frames.

use std::time::Duration;

use crate::controllers::{Devices, Jack};
use crate::live_show::{Show, VirtualDisplay, scratch_dir};

/// A show whose timeline starts at 01:00:00:00, at 60 steps a second.
const SHOW: &str = r#"(
    name: "chaser", size: (32, 32),
    layers: [(name: "one", clips: [(scene: "kleinian")])],
    timeline: (chase: (start: "01:00:00:00", freewheel: 2.0)),
)"#;

/// 01:00:00:00 at 25 fps.
const HOUR: u64 = 3600 * 25;

/// One of the show's chase lines: wall clock, the code's position (timeline seconds), the
/// frame it wants, the frame shown, and the state.
#[derive(Debug)]
struct Line {
    unix: f64,
    code: f64,
    wants: u64,
    shows: u64,
    state: String,
}

/// The chase lines of the show's log, and the log's other lines with their place among them.
fn chase_lines(log: &str) -> (Vec<Line>, Vec<(usize, String)>) {
    let (mut lines, mut others) = (Vec::new(), Vec::new());
    for text in log.lines() {
        let Some(rest) = text.split("indra::chase] unix ").nth(1) else {
            others.push((lines.len(), text.to_string()));
            continue;
        };
        let w: Vec<&str> = rest.split_whitespace().collect();
        let [unix, "code", code, "s", "wants", wants, "shows", shows, state] = w.as_slice() else {
            panic!("a chase line of another shape: {text}")
        };
        lines.push(Line {
            unix: unix.parse().unwrap(),
            code: code.parse().unwrap(),
            wants: wants.parse().unwrap(),
            shows: shows.parse().unwrap(),
            state: state.to_string(),
        });
    }
    (lines, others)
}

/// One run of the desk's code: from wall-clock time `began` to `ended`, with stamps
/// (wall-clock time, timeline seconds the code said then) between which the code runs at 1 s/s.
#[derive(Clone, Debug)]
struct Run {
    stamps: Vec<(f64, f64)>,
    began: f64,
    ended: f64,
}

impl Run {
    /// A desk that runs from `frame` (a 25 fps count) from `began` on its own clock.
    fn from(frame: u64, began: f64, ended: f64) -> Self {
        Run { stamps: vec![(began, (frame - HOUR) as f64 / 25.0)], began, ended }
    }

    /// The timeline's seconds the desk's code says at `unix`.
    fn seconds(&self, unix: f64) -> f64 {
        let i = self.stamps.partition_point(|&(t, _)| t <= unix).max(1) - 1;
        let (t, seconds) = self.stamps[i];
        seconds + (unix - t)
    }
}

fn start_mtc(devices: &mut Devices, frame: u64) -> f64 {
    devices.command(&format!("mtc desk 25 {frame}")).as_f64().expect("the desk answers when it began")
}

fn now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64()
}

/// A run's locked lines, past its first 0.2 s (which read the first whole label).
fn locked<'a>(lines: &'a [Line], run: &Run) -> Vec<&'a Line> {
    lines.iter().filter(|l| l.unix > run.began + 0.2 && l.unix < run.ended && l.state == "locked").collect()
}

/// How far the show's code is from the desk's over a run's locked lines: the median and the
/// 90th percentile, in seconds.
fn errors(lines: &[Line], run: &Run) -> (f64, f64, usize) {
    let mut errors: Vec<f64> = locked(lines, run).iter().map(|l| (l.code - run.seconds(l.unix)).abs()).collect();
    errors.sort_by(f64::total_cmp);
    assert!(errors.len() > 20, "{} locked frames in the run {run:?}", errors.len());
    (errors[errors.len() / 2], errors[errors.len() * 9 / 10], errors.len())
}

/// What a chase of three runs — a run, a jump back and a run, a dropout of 1 s and the code on
/// where it had got to, then a stop — must show in the show's log. `back_to`: the frames the
/// seek at the jump back may aim at (the code runs on while it is read).
fn check_chase(log: &str, runs: [Run; 3], back_to: std::ops::RangeInclusive<u64>) {
    let (lines, others) = chase_lines(log);
    assert!(lines.len() > 200, "{} chase lines:\n{log}", lines.len());
    let [first, second, third] = &runs;

    // Locked, the show hears the desk's code within a frame of it, and once on the code's frame
    // (past a seek: the first code is a jump from frame 0) shows the frame it says.
    for run in &runs {
        let (median, p90, count) = errors(&lines, run);
        eprintln!(
            "run {:.2}..{:.2}: {count} frames, code off the desk's by {median:.4} s median, {p90:.4} s p90",
            run.began, run.ended
        );
        assert!(median < 0.02 && p90 < 0.04, "code off by {median:.4} s median, {p90:.4} s p90 in {run:?}");
        let locked: Vec<&Line> = locked(&lines, run).into_iter().skip_while(|l| l.shows != l.wants).collect();
        let on_it = locked.iter().filter(|l| l.shows == l.wants).count();
        assert!(locked.len() > 20, "the show reached the code's frame late or never in {run:?}");
        // Three in four: on CI's two busy cores the window drops frames and the desk's JACK cycles
        // come late (86 % there once), while the code's time above stays within a frame.
        assert!(on_it * 4 >= locked.len() * 3, "{on_it} of {} locked frames show the code's frame", locked.len());
        let last = locked.last().unwrap();
        assert!(last.shows.abs_diff((run.seconds(last.unix) * 60.0) as u64) <= 3, "{last:?} in {run:?}");
    }

    // The first code and the jump back are seeks, made off the render thread; after each the
    // show is back on the code.
    let jumped: Vec<&(usize, String)> = others.iter().filter(|(_, t)| t.contains("the code jumped to frame")).collect();
    assert_eq!(jumped.len(), 2, "a seek to the first code and one at the jump back: {jumped:?}");
    let target: u64 =
        jumped[1].1.split("jumped to frame ").nth(1).and_then(|t| t.split(' ').next()).unwrap().parse().unwrap();
    assert!(back_to.contains(&target), "{}", jumped[1].1);
    let sought: Vec<&(usize, String)> = others.iter().filter(|(_, t)| t.contains("timecode: sought frame")).collect();
    assert_eq!(sought.len(), 2, "{sought:?}");
    let after = &lines[sought[1].0..];
    assert!(after.first().is_some_and(|l| l.unix < second.began + 3.0), "the seek took until {:?}", after.first());

    // Through the dropout the show runs on, frame after frame, and takes the code again without
    // a seek: where the code comes back is where the show had got to.
    let gap: Vec<&Line> = lines.iter().filter(|l| l.unix > second.ended + 0.2 && l.unix < third.began).collect();
    assert!(gap.iter().all(|l| l.state == "freewheel"), "{gap:?}");
    assert!(gap.windows(2).all(|w| w[1].shows >= w[0].shows) && gap.last().unwrap().shows > gap[0].shows + 30);

    // Stopped for good, past the freewheel the frame holds.
    let held: Vec<&Line> = lines.iter().filter(|l| l.unix > third.ended + 2.3).collect();
    assert!(!held.is_empty() && held.iter().all(|l| l.state == "stopped" && l.shows == held[0].shows), "{held:?}");
    assert!(first.ended <= second.began);
}

/// The show's environment: the test's JACK server, and the chase's debug lines.
fn show_env(jack: &Jack) -> [(&str, &std::ffi::OsStr); 2] {
    [("JACK_DEFAULT_SERVER", jack.name.as_ref()), ("RUST_LOG", "info,indra::chase=debug".as_ref())]
}

#[test]
fn a_show_chases_mtc_through_a_jump_a_dropout_and_a_stop() {
    let Some(jack) = Jack::start() else { return };
    let Some(mut devices) = Devices::start(&jack, &["desk=desk out,desk in"]) else { return };
    let display = VirtualDisplay::start();
    let dir = scratch_dir("mtc-in");
    let file = dir.join("chaser.ron");
    std::fs::write(&file, SHOW).unwrap();
    let args: Vec<&std::ffi::OsStr> = ["--mtc-in", "--midi", "desk"].iter().map(|a| a.as_ref()).collect();
    let (mut show, _) = Show::start_with_midi(&display, &dir, file.to_str().unwrap(), &args, &show_env(&jack));
    show.wait_for("MIDI in: desk");
    std::thread::sleep(Duration::from_secs(1));

    // Runs from 01:00:10:00 for 3 s.
    let began = start_mtc(&mut devices, HOUR + 250);
    std::thread::sleep(Duration::from_secs(3));
    assert_eq!(devices.command("mtc-stop desk"), "stopped");
    let first = Run::from(HOUR + 250, began, now());
    // Locates back to 01:00:02:00 (a full frame), and runs from there.
    devices.send("desk", &[0xF0, 0x7F, 0x7F, 0x01, 0x01, 0x21, 0, 2, 0, 0xF7]);
    std::thread::sleep(Duration::from_millis(300));
    let began = start_mtc(&mut devices, HOUR + 50);
    std::thread::sleep(Duration::from_secs(4));
    assert_eq!(devices.command("mtc-stop desk"), "stopped");
    let second = Run::from(HOUR + 50, began, now());
    // A dropout of 1 s (the show freewheels 2 s), then the desk goes on where its code is.
    std::thread::sleep(Duration::from_secs(1));
    let on = (second.seconds(now() + 0.01) * 25.0).ceil() as u64 + HOUR;
    let on = on + on % 2;
    let began = start_mtc(&mut devices, on);
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(devices.command("mtc-stop desk"), "stopped");
    let third = Run::from(on, began, now());
    // It stops for good: past the freewheel the show holds.
    std::thread::sleep(Duration::from_secs(3));
    show.interrupt();
    // The locate stands at 01:00:02:00: the seek aims at its frame.
    check_chase(&std::fs::read_to_string(&show.log).unwrap(), [first, second, third], 120..=120);
}

/// The LTC the desk plays, as libltc's segments (see tests/timecode/ltcgen.c) at 25 fps: 3 s
/// from 01:00:10:00, a jump back to 01:00:02:00 and 4 s on, a dropout of 1 s, 2 s from where
/// the code had got to, and silence.
const LTC_SEGMENTS: [&str; 5] = ["01:00:10:00+75", "01:00:02:00+100", "silence+25", "01:00:07:00+50", "silence+100"];

/// Samples a code frame lasts at 48 kHz and 25 fps.
const FRAME_SAMPLES: u64 = 48_000 / 25;

#[test]
fn a_show_chases_ltc_on_its_audio_input_through_a_jump_a_dropout_and_a_stop() {
    if !cfg!(feature = "jack") {
        return crate::controllers::skip("this test build has no JACK audio (tools/test builds with --features jack)");
    }
    let Some(ltcgen) = crate::timecode::ltcgen() else { return };
    let Some(jack) = Jack::start() else { return };
    let Some(mut devices) = Devices::start(&jack, &["desk=desk out,desk in"]) else { return };
    let display = VirtualDisplay::start();
    let dir = scratch_dir("ltc-in");
    let file = dir.join("chaser.ron");
    std::fs::write(&file, SHOW).unwrap();
    let code = dir.join("ltc.u8");
    let out = std::process::Command::new(ltcgen).args(["48000", "25"]).args(LTC_SEGMENTS).output().unwrap();
    assert!(out.status.success(), "ltcgen: {}", String::from_utf8_lossy(&out.stderr));
    std::fs::write(&code, &out.stdout).unwrap();
    // The code on the input's second channel; the first hears the (silent) dummy capture.
    let args: Vec<&std::ffi::OsStr> = ["--ltc-in", "--ltc-channel", "2"].iter().map(|a| a.as_ref()).collect();
    let (mut show, _) = Show::start_with_midi(&display, &dir, file.to_str().unwrap(), &args, &show_env(&jack));
    show.wait_for("audio input: ");
    std::thread::sleep(Duration::from_secs(1));

    let play = format!("play desk {} cpal_client_.*_in:in_1", code.display());
    assert_eq!(devices.command(&play), "playing");
    // Where the desk's file was at each cycle, on the wall clock, until it has played to its end:
    // 14 s of code, longer where a busy machine runs JACK's cycles late.
    let length = out.stdout.len() as u64;
    let mut cycles: Vec<(f64, u64)> = Vec::new();
    let deadline = std::time::Instant::now() + Duration::from_secs(90);
    while cycles.last().is_none_or(|&(_, at)| at < length) {
        assert!(
            std::time::Instant::now() < deadline,
            "the desk played {:?} of {length} samples in 90 s",
            cycles.last()
        );
        std::thread::sleep(Duration::from_millis(500));
        let played = devices.command("played desk");
        cycles.extend(played.as_array().unwrap().iter().map(|c| (c[0].as_f64().unwrap(), c[1].as_u64().unwrap())));
    }
    show.interrupt();
    assert!(cycles.len() > 1000, "{} cycles played", cycles.len());
    // A segment of the file: its first label (a 25 fps count) and its samples.
    let run = |frame: u64, from: u64, to: u64| {
        let within: Vec<&(f64, u64)> = cycles.iter().filter(|&&(_, s)| s >= from && s < to).collect();
        let stamps = within.iter().map(|&&(t, s)| (t, (frame - HOUR) as f64 / 25.0 + (s - from) as f64 / 48_000.0));
        let ended = cycles.iter().find(|&&(_, s)| s >= to).expect("the file played to its end").0;
        Run { stamps: stamps.collect(), began: within[0].0, ended }
    };
    let s = |frames: u64| frames * FRAME_SAMPLES;
    let runs = [run(HOUR + 250, 0, s(75)), run(HOUR + 50, s(75), s(175)), run(HOUR + 175, s(200), s(250))];
    // The code runs on while the jump is read: the seek aims a few frames past 01:00:02:00.
    check_chase(&std::fs::read_to_string(&show.log).unwrap(), runs, 120..=130);
}
