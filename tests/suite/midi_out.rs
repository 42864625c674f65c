//! MIDI out on a real port (JACK's dummy driver, as the controller tests): a desk — a JACK
//! client from PyPI's JACK-Client — receives every MIDI-mapped parameter as its control change
//! when the value changes from any source (OSC here, and the desk's own fader), 14-bit mappings
//! as MSB/LSB pairs, and MIDI clock at the show's tempo.

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

#[test]
fn mapped_parameters_and_the_clock_go_out_to_a_desk() {
    let Some(jack) = Jack::start() else { return };
    let Some(mut devices) = Devices::start(&jack, &["desk=desk out,desk in"]) else { return };
    let display = VirtualDisplay::start();
    let dir = scratch_dir("midi-out");
    let file = dir.join("desk.ron");
    std::fs::write(&file, SHOW).unwrap();
    let args = ["--midi-out".as_ref(), "desk in".as_ref(), "--midi-clock".as_ref()];
    let env = [("JACK_DEFAULT_SERVER", jack.name.as_ref())];
    let (mut show, osc) = Show::start_with_midi(&display, &dir, file.to_str().unwrap(), &args, &env);
    show.wait_for("MIDI out: desk:desk in connected");
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
