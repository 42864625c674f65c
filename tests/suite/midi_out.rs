//! MIDI out on a real port (JACK's dummy driver, as the controller tests): a desk — a JACK
//! client from PyPI's JACK-Client — receives every MIDI-mapped parameter as its control change
//! when the value changes from any source (OSC here, and the desk's own fader), 14-bit mappings
//! as MSB/LSB pairs, and MIDI clock at the show's tempo; and the show as the timecode master,
//! MTC on the MIDI port and LTC on a JACK audio output.

use std::net::UdpSocket;
use std::time::Duration;

use rosc::OscType;

use crate::controllers::{Devices, Jack};
use crate::live_show::{Show, VirtualDisplay, scratch_dir, send};

/// One layer; its opacity on CC 1, the master on a 14-bit CC 2/34; 150 BPM (a clock pulse
/// every 16.7 ms).
const SHOW: &str = r#"(
    name: "desk", size: (32, 32), bpm: 150.0,
    layers: [(name: "one", clips: [(scene: "kleinian")])],
    controls: (midi: [(cc: 1, target: "layer/1.opacity"), (cc: 2, fine: true, target: "master.level")]),
)"#;

/// A show playing to a desk on a JACK MIDI port (fields drop in order: the show first).
struct Desk {
    show: Show,
    osc: u16,
    devices: Devices,
    _display: VirtualDisplay,
    _jack: Jack,
}

/// `show` (a show file's text) started with `args`, its MIDI out connected to the desk; `None`
/// (skipped) without JACK or its Python client.
fn play_to_desk(name: &str, show: &str, args: &[&str]) -> Option<Desk> {
    let jack = Jack::start()?;
    let devices = Devices::start(&jack, &["desk=desk out,desk in"])?;
    let display = VirtualDisplay::start();
    let dir = scratch_dir(name);
    let file = dir.join(format!("{name}.ron"));
    std::fs::write(&file, show).unwrap();
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_ref()).collect();
    let env = [("JACK_DEFAULT_SERVER", jack.name.as_ref())];
    let (mut show, osc) = Show::start_with_midi(&display, &dir, file.to_str().unwrap(), &args, &env);
    show.wait_for("MIDI out: desk:desk in connected");
    Some(Desk { show, osc, devices, _display: display, _jack: jack })
}

#[test]
fn mapped_parameters_and_the_clock_go_out_to_a_desk() {
    let Some(desk) = play_to_desk("midi-out", SHOW, &["--midi-out", "desk in", "--midi-clock"]) else { return };
    let Desk { mut show, osc, mut devices, .. } = desk;
    // At connect: every mapped value (opacity 1.0, level 1.0 as 16383) and the clock's Start.
    let seen = devices.wait_for_all("desk", &[&[0xB0, 1, 127], &[0xB0, 2, 127], &[0xB0, 34, 127], &[0xFA]]);
    let start = seen.iter().position(|(_, m)| m == &[0xFA]).unwrap();
    assert!(!seen[..start].iter().any(|(_, m)| m == &[0xF8]), "a pulse came before Start");
    // A change from OSC goes out; the desk's own fader comes back as itself.
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    send(&socket, osc, "/indra/layer/1/opacity", vec![OscType::Float(0.5)]);
    devices.wait_for("desk", &[0xB0, 1, 64]);
    send(&socket, osc, "/indra/master", vec![OscType::Float(0.25)]);
    // 0.25 × 16383 = 4095.75 → 4096: MSB 32, LSB 0.
    devices.wait_for_all("desk", &[&[0xB0, 2, 32], &[0xB0, 34, 0]]);
    devices.send("desk", &[0xB0, 1, 20]);
    devices.wait_for("desk", &[0xB0, 1, 20]);
    // The clock: 24 pulses a beat at 150 BPM.
    devices.take("desk");
    std::thread::sleep(Duration::from_secs(3));
    let pulses: Vec<f64> = devices.take("desk").into_iter().filter(|(_, m)| m == &[0xF8]).map(|(t, _)| t).collect();
    // Pulses follow the show's beat; on a machine busy with other tests a frame may stall (the
    // clock then slows with the show) and JACK's cycles run late and then back to back (pulses
    // arrive bunched, so single gaps say little). So the rate over three seconds is held to 8 %:
    // enough to catch a clock at another tempo, or another count of pulses a beat.
    let span = pulses.last().unwrap() - pulses.first().unwrap();
    let bpm = (pulses.len() - 1) as f64 / span * 60.0 / 24.0;
    assert!((bpm / 150.0 - 1.0).abs() < 0.08, "{} pulses in {span:.3} s: {bpm:.1} BPM", pulses.len());
    assert!(show.child.try_wait().unwrap().is_none(), "the show is still running");
}

/// A show whose timeline starts at 01:00:00:00.
const TIMELINE_SHOW: &str = r#"(
    name: "master", size: (32, 32),
    layers: [(name: "one", clips: [(scene: "kleinian")])],
    timeline: (chase: (start: "01:00:00:00")),
)"#;

/// The labels a run of MTC quarter frames spells (piece 0 to 7 in order), read here without
/// indra's MTC reader: (arrival, frame count at 25 fps, the rate code of the hours nibble).
fn quarter_frame_labels(messages: &[(f64, Vec<u8>)]) -> Vec<(f64, u64, u8)> {
    let mut labels = Vec::new();
    let mut pieces = Vec::new();
    for (t, m) in messages {
        let [0xF1, data] = m.as_slice() else { continue };
        let (piece, nibble) = (usize::from(data >> 4), u64::from(data & 0xF));
        if piece != pieces.len() {
            pieces.clear();
            if piece != 0 {
                continue;
            }
        }
        pieces.push(nibble);
        if pieces.len() == 8 {
            let p = &pieces;
            let (frames, seconds) = (p[0] | (p[1] & 1) << 4, p[2] | (p[3] & 3) << 4);
            let (minutes, hours) = (p[4] | (p[5] & 3) << 4, p[6] | (p[7] & 1) << 4);
            labels.push((*t, ((hours * 60 + minutes) * 60 + seconds) * 25 + frames, (p[7] >> 1) as u8));
            pieces.clear();
        }
    }
    labels
}

#[test]
fn the_show_is_the_timecode_master_over_mtc_and_ltc() {
    if !cfg!(feature = "jack") {
        return crate::controllers::skip("this test build has no JACK audio (tools/test builds with --features jack)");
    }
    let Some(ltcread) = crate::timecode::ltcread() else { return };
    let args = ["--midi-out", "desk in", "--mtc-out", "25", "--ltc-out", "25"];
    let Some(desk) = play_to_desk("mtc-out", TIMELINE_SHOW, &args) else { return };
    let Desk { mut show, mut devices, .. } = desk;
    show.wait_for("LTC out at 25 fps");
    assert_eq!(devices.command("record desk cpal_client_.*_out:out_0"), "recording");
    // The code starts with a full frame locating the desk in the timeline's first hour.
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    let mut seen = Vec::new();
    while !seen.iter().any(|(_, m): &(f64, Vec<u8>)| m.first() == Some(&0xF1)) {
        assert!(std::time::Instant::now() < deadline, "no MTC came: {seen:02x?}");
        std::thread::sleep(Duration::from_millis(50));
        seen.extend(devices.take("desk"));
    }
    let located = seen.iter().find(|(_, m)| m.first() == Some(&0xF0)).expect("a full-frame message first");
    let [0xF0, 0x7F, 0x7F, 0x01, 0x01, hh, ..] = located.1.as_slice() else { panic!("{:?}", located.1) };
    assert_eq!((hh >> 5, hh & 0x1F), (1, 1), "25 fps, hour 1");
    devices.take("desk");
    std::thread::sleep(Duration::from_secs(3));
    let messages = devices.take("desk");
    let labels = quarter_frame_labels(&messages);
    assert!(labels.len() >= 30, "{} whole labels in 3 s", labels.len());
    // Each label two frames after the one before (eight quarter frames), at 25 fps. A frame
    // stalled on a busy machine may make the code locate again (a full frame) once.
    let locates = messages.iter().filter(|(_, m)| m.first() == Some(&0xF0)).count();
    let steps: Vec<u64> = labels.windows(2).map(|pair| pair[1].1.wrapping_sub(pair[0].1)).collect();
    let breaks = steps.iter().filter(|&&step| step != 2).count();
    assert!(breaks <= locates && locates <= 1, "{locates} locates, label steps {steps:?}");
    assert!(labels.iter().all(|label| label.2 == 1), "the rate code says 25 fps");
    // The code runs at the show's pace: held to 8 % over three seconds, as the clock is.
    let (first, last) = (labels[0], labels[labels.len() - 1]);
    let fps = (last.1 - first.1) as f64 / (last.0 - first.0);
    assert!((fps / 25.0 - 1.0).abs() < 0.08, "{fps:.2} frames a second");
    assert!(first.1 >= 3600 * 25 && first.1 < 3600 * 25 + 60 * 25, "code {} is in the show's first minute", first.1);
    assert!(show.child.try_wait().unwrap().is_none(), "the show is still running");

    // The LTC it sent meanwhile on its audio output, read by libltc: frame after frame at
    // 25 fps, each label where the MTC (its own follower of the show's position) put the show
    // when the frame began.
    let recording = scratch_dir("ltc-out").join("ltc.s16");
    let cycles = devices.command(&format!("recorded desk {}", recording.display()));
    let cycles: Vec<(f64, u64)> =
        cycles.as_array().unwrap().iter().map(|c| (c[0].as_f64().unwrap(), c[1].as_u64().unwrap())).collect();
    let read = std::process::Command::new(ltcread)
        .args(["48000", "25"])
        .stdin(std::fs::File::open(&recording).unwrap())
        .output()
        .unwrap();
    let frames: Vec<(u64, u64)> = String::from_utf8(read.stdout)
        .unwrap()
        .lines()
        .map(|line| {
            let w: Vec<&str> = line.split(' ').collect();
            let label = indra::timecode::Timecode::parse(w[0]).unwrap();
            (indra::timecode::Rate::Fps25.count(label).unwrap(), w[1].parse().unwrap())
        })
        .collect();
    // 75 at most: on CI's two busy cores JACK's cycles come late and a frame or a few are lost
    // (69 read there once); how the labels run and where they fall is checked below.
    assert!(frames.len() >= 55, "{} LTC frames read in over 3 s", frames.len());
    let steps = frames.windows(2).filter(|w| w[1].0 != w[0].0 + 1).count();
    // Where the audio clock lost time against the wall clock (JACK's dummy driver runs its
    // cycles late on a busy machine, and the samples do not catch up), the code falls behind the
    // show, and the labels jump forward to it, as they must: a break for each frame lost is
    // allowed beside the MTC's locates. On a quiet machine nothing is lost and none is.
    let (first_cycle, last_cycle) = (cycles[0], cycles[cycles.len() - 1]);
    let lost = (last_cycle.0 - first_cycle.0) - (last_cycle.1 - first_cycle.1) as f64 / 48_000.0;
    let allowed = locates + (lost.max(0.0) * 25.0).ceil() as usize;
    assert!(
        steps <= allowed,
        "{steps} breaks in the LTC labels with {locates} MTC locates and {:.0} ms of audio time lost",
        lost * 1e3
    );
    // When sample `s` of the recording came: the cycle it was in, on the cycle's clock.
    let time_of = |s: u64| {
        let i = cycles.partition_point(|&(_, first)| first <= s).max(1) - 1;
        cycles[i].0 + (s - cycles[i].1) as f64 / 48_000.0
    };
    // The MTC's position then: a label's last quarter frame comes 1.75 frames into it.
    let mtc_at = |t: f64| {
        let i = labels.partition_point(|l| l.0 <= t).max(1) - 1;
        labels[i].1 as f64 + 1.75 + (t - labels[i].0) * 25.0
    };
    let mut gaps: Vec<f64> = (frames.iter())
        .map(|&(label, start)| (time_of(start), label))
        .filter(|&(t, _)| t > labels[0].0 && t < labels[labels.len() - 1].0)
        .map(|(t, label)| label as f64 - mtc_at(t))
        .collect();
    gaps.sort_by(f64::total_cmp);
    assert!(gaps.len() >= 50, "{} LTC frames beside the MTC", gaps.len());
    let (median, p90) = (gaps[gaps.len() / 2], gaps[gaps.len() * 9 / 10].abs().max(gaps[gaps.len() / 10].abs()));
    // Audio time lost (above) puts the code behind by as much, up to the two frames past which
    // it jumps, until its vari-speed (2 %) has caught up: the tolerance grows by that much.
    let behind = (lost.max(0.0) * 25.0).min(2.0);
    eprintln!(
        "LTC against MTC: {median:+.2} frames median, {p90:.2} at the 10th/90th percentile; {:.0} ms of audio time lost",
        lost * 1e3
    );
    assert!(
        median.abs() < 0.5 + behind && p90 < 0.75 + behind,
        "LTC off the MTC by {median:+.2} frames median, {p90:.2} p10/p90, with {:.0} ms of audio time lost",
        lost * 1e3
    );
}
