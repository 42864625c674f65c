//! MIDI out, the mirror of MIDI in: every parameter with a MIDI mapping (the scene's, or learned)
//! is sent back as its control change (7-bit, or 14-bit as an MSB/LSB pair) or note whenever its
//! value changes, from whatever source — so motor faders, LED rings and other gear follow indra —
//! and, when asked, MIDI clock at the show's tempo, its pulses on the show's own beat (so a Link
//! session's phase, when Link drives the tempo), and MTC for the show's position
//! ([`super::mtc_out`]). A thread owns the port: the render thread only queues messages (bounded)
//! and offers its beat and position.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::midi::Binding;
use super::mtc_out::code_seconds;
use crate::params::{ParamType, ParamValue, TempoClock};
use crate::scene::{MidiCurve, SceneView};
use crate::timecode::Rate;

/// Messages waiting for the port at most; past that a frame's changes are dropped and counted.
const QUEUE: usize = 4096;
/// Clock pulses a quarter note.
#[cfg(feature = "midi")]
const PPQN: f64 = 24.0;

/// The 0–1 control position of a parameter's value through its mapping: the inverse of MIDI
/// in's scaling (range, curve, inversion), so a value sent out comes back in as itself.
pub fn position(value: ParamValue, binding: &Binding, view: &SceneView<'_>) -> Option<f32> {
    let m = &binding.mapping;
    let decl = view.scene.nodes.get(binding.target.node)?.params.decls().get(binding.target.param)?;
    let (lo, hi) = m.range.or(decl.range).unwrap_or((0.0, 1.0));
    let number = |x: f32| match m.curve {
        MidiCurve::Exponential if lo > 0.0 && hi > 0.0 && x > 0.0 => (x / lo).ln() / (hi / lo).ln(),
        MidiCurve::Exponential => ((x - lo) / (hi - lo)).max(0.0).sqrt(),
        MidiCurve::Linear => (x - lo) / (hi - lo),
    };
    let pos = match (binding.target.component, value) {
        (Some(c), v) => number(*v.components().get(c)?),
        (None, ParamValue::Bool(b)) => f32::from(u8::from(b)),
        (None, ParamValue::Enum(i)) => i as f32 / decl.options.len().saturating_sub(1).max(1) as f32,
        (None, ParamValue::Trigger(_) | ParamValue::Text(_)) => return None,
        (None, v) if decl.ty() == ParamType::Float || decl.ty() == ParamType::Int => number(*v.components().first()?),
        _ => return None,
    };
    let pos = if pos.is_finite() { pos.clamp(0.0, 1.0) } else { 0.0 };
    Some(if m.invert { 1.0 - pos } else { pos })
}

/// The messages (one, or a 14-bit pair) that put binding's control where `pos` (0–1) is.
pub fn messages(binding: &Binding, pos: f32) -> [Option<[u8; 3]>; 2] {
    let m = &binding.mapping;
    let channel = m.channel.unwrap_or(1).clamp(1, 16) - 1;
    match (m.cc, m.note) {
        (Some(cc), _) if m.fine => {
            let v = (pos * 16383.0).round() as u16;
            [Some([0xB0 | channel, cc, (v >> 7) as u8]), Some([0xB0 | channel, cc + 32, (v & 0x7F) as u8])]
        }
        (Some(cc), _) => [Some([0xB0 | channel, cc, (pos * 127.0).round() as u8]), None],
        (None, Some(note)) => match (pos * 127.0).round() as u8 {
            0 => [Some([0x80 | channel, note, 0]), None],
            velocity => [Some([0x90 | channel, note, velocity]), None],
        },
        (None, None) => [None, None],
    }
}

/// What the thread shares with the render thread.
#[derive(Default)]
struct Shared {
    /// The show's tempo at an instant, for the clock.
    beat: Mutex<Option<(TempoClock, Instant)>>,
    /// The show's position in code seconds at an instant, for MTC.
    position: Mutex<Option<(f64, Instant)>>,
    /// Messages sent.
    sent: AtomicU64,
    /// Messages dropped on a full queue.
    dropped: AtomicU64,
    connected: AtomicBool,
    stop: AtomicBool,
}

/// MIDI out to one port: the mirror of the mappings, and the clock when asked.
pub struct MidiOut {
    queue: SyncSender<Vec<u8>>,
    shared: Arc<Shared>,
    /// Per binding (scene's then learned, as the mapper lists them): the messages last sent.
    last: Vec<[Option<[u8; 3]>; 2]>,
    thread: Option<JoinHandle<()>>,
    clock: bool,
    mtc: Option<Rate>,
}

impl MidiOut {
    /// Sends to the first output port whose name contains `port` (connecting when it appears);
    /// with `clock`, MIDI clock too (Start, then 24 pulses a beat); with `mtc`, MTC at that rate.
    pub fn start(port: &str, clock: bool, mtc: Option<Rate>) -> Result<Self, String> {
        let (queue, messages) = sync_channel(QUEUE);
        let shared = Arc::new(Shared::default());
        let (thread_shared, port) = (Arc::clone(&shared), port.to_lowercase());
        let thread = std::thread::Builder::new()
            .name("indra-midi-out".into())
            .spawn(move || run(&port, clock, mtc, &messages, &thread_shared))
            .map_err(|e| format!("cannot start the MIDI out thread: {e}"))?;
        Ok(Self { queue, shared, last: Vec::new(), thread: Some(thread), clock, mtc })
    }

    /// After a frame at `seconds` of the show: queues the mapped parameters whose control
    /// position changed, and offers the tempo to the clock and the position to MTC (never
    /// waiting for their locks).
    pub fn after_frame(&mut self, bindings: &[Binding], view: &SceneView<'_>, seconds: f64) {
        // A learned or unlearned binding shifts the list: what follows it is sent once more.
        self.last.resize(bindings.len(), [None, None]);
        for (binding, last) in bindings.iter().zip(&mut self.last) {
            let value = view.params(binding.target.node).target_at(binding.target.param);
            let Some(pos) = position(value, binding, view) else { continue };
            let out = messages(binding, pos);
            if *last == out {
                continue;
            }
            let bytes: Vec<u8> = out.iter().flatten().flatten().copied().collect();
            if self.queue.try_send(bytes).is_ok() {
                *last = out;
            } else {
                self.shared.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
        if self.clock
            && let Ok(mut beat) = self.shared.beat.try_lock()
        {
            *beat = Some((view.tempo, Instant::now()));
        }
        if let Some(rate) = self.mtc
            && let Ok(mut position) = self.shared.position.try_lock()
        {
            *position = Some((code_seconds(view, seconds, rate), Instant::now()));
        }
    }

    /// Forgets what was sent (a new scene: everything is sent again).
    pub fn reset(&mut self) {
        self.last.clear();
    }

    /// For the status line.
    pub fn status(&self) -> String {
        let s = &self.shared;
        let state = if s.connected.load(Ordering::Relaxed) { "connected" } else { "waiting for its port" };
        let (sent, dropped) = (s.sent.load(Ordering::Relaxed), s.dropped.load(Ordering::Relaxed));
        let clock = if self.clock { ", clock" } else { "" };
        let mtc = self.mtc.map(|rate| format!(", MTC at {rate}")).unwrap_or_default();
        format!("MIDI out {state}: {sent} sent, {dropped} dropped{clock}{mtc}")
    }
}

impl Drop for MidiOut {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The thread: keeps the port connected, sends queued messages, clock pulses and MTC.
#[cfg(feature = "midi")]
fn run(port: &str, clock: bool, mtc: Option<Rate>, messages: &Receiver<Vec<u8>>, shared: &Shared) {
    let mut output: Option<(String, midir::MidiOutputConnection)> = None;
    // Lists the ports (kept: a JACK client a second would churn the server).
    let mut probe: Option<midir::MidiOutput> = None;
    let mut last_scan: Option<Instant> = None;
    let mut clock_state = ClockFollower::default();
    let mut code = mtc.map(super::mtc_out::MtcFollower::new);
    while !shared.stop.load(Ordering::Relaxed) {
        if last_scan.is_none_or(|t| t.elapsed() >= Duration::from_secs(1)) {
            last_scan = Some(Instant::now());
            if probe.is_none() {
                probe = midir::MidiOutput::new(super::controller::port::CLIENT).ok();
            }
            output = probe.as_ref().and_then(|probe| reconnect(probe, output, port));
            shared.connected.store(output.is_some(), Ordering::Relaxed);
        }
        let Some((_, connection)) = output.as_mut() else {
            // Nothing to send to: what waits is stale by the time a port comes.
            while messages.try_recv().is_ok() {}
            std::thread::sleep(Duration::from_millis(20));
            continue;
        };
        let mut send = |bytes: &[u8]| {
            if connection.send(bytes).is_ok() {
                shared.sent.fetch_add(1, Ordering::Relaxed);
            }
        };
        for bytes in messages.try_iter() {
            for message in bytes.chunks(3) {
                send(message);
            }
        }
        let beat = shared.beat.lock().ok().and_then(|b| *b);
        if clock && let Some((tempo, at)) = beat {
            let (start, pulses) = clock_state.advance(tempo, at, Instant::now());
            if start {
                send(&[0xFA]);
            }
            (0..pulses).for_each(|_| send(&[0xF8]));
        }
        let position = shared.position.lock().ok().and_then(|p| *p);
        if let (Some(code), Some((seconds, at))) = (code.as_mut(), position) {
            code.advance(seconds, at, Instant::now(), &mut send);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    if clock && let Some((_, connection)) = output.as_mut() {
        let _ = connection.send(&[0xFC]);
    }
}

/// The clock's own beat: it runs at the show's tempo in real time and is pulled gently toward
/// the beat the frames report (each frame's report is late by its own render time, which varies:
/// following each one would jump the clock, dropping or doubling pulses). A report a beat or more
/// away is a seek or a jump, taken at once.
#[cfg(feature = "midi")]
#[derive(Default)]
struct ClockFollower {
    /// The clock's beat at an instant.
    beat: Option<(f64, Instant)>,
    /// The last pulse sent, counted from beat 0.
    pulse: i64,
}

/// The share of the gap to the reported beat closed each millisecond (about half a second's
/// time constant).
#[cfg(feature = "midi")]
const PULL: f64 = 0.002;
/// Pulses sent at once at most after a stall of the thread; a longer stall skips ahead.
#[cfg(feature = "midi")]
const MAX_BURST: i64 = 12;

#[cfg(feature = "midi")]
impl ClockFollower {
    /// Moves the clock to `now` against the show's `tempo` reported at `at`: whether to send
    /// Start, and how many pulses.
    fn advance(&mut self, tempo: TempoClock, at: Instant, now: Instant) -> (bool, i64) {
        let per_second = tempo.bpm / 60.0;
        let reported = tempo.beats + now.saturating_duration_since(at).as_secs_f64() * per_second;
        let Some((beat, then)) = self.beat else {
            self.beat = Some((reported, now));
            self.pulse = (reported * PPQN).floor() as i64;
            return (true, 0);
        };
        let elapsed = now.saturating_duration_since(then).as_secs_f64();
        let mut own = beat + elapsed * per_second;
        let gap = reported - own;
        let jumped = gap.abs() >= 1.0;
        own = if jumped { reported } else { own + gap * (PULL * elapsed * 1000.0).min(1.0) };
        self.beat = Some((own, now));
        let target = (own * PPQN).floor() as i64;
        let pulses = target - self.pulse;
        if jumped || pulses > MAX_BURST {
            // No burst after a seek or a stall: the clock goes on from here.
            self.pulse = target;
            return (false, 0);
        }
        if pulses <= 0 {
            // Pulled back a little: the pulses already sent are not sent twice.
            return (false, 0);
        }
        self.pulse = target;
        (false, pulses)
    }
}

/// Keeps `output` while its port is there; else connects to the first port matching `port`.
#[cfg(feature = "midi")]
fn reconnect(
    probe: &midir::MidiOutput,
    output: Option<(String, midir::MidiOutputConnection)>,
    port: &str,
) -> Option<(String, midir::MidiOutputConnection)> {
    let ports = super::controller::port::named_ports(probe);
    if let Some((name, connection)) = output {
        if ports.iter().any(|(_, n)| *n == name) {
            return Some((name, connection));
        }
        connection.close();
        log::info!("MIDI out: {name} went away");
    }
    let (found, name) = ports.into_iter().find(|(_, n)| n.to_lowercase().contains(port))?;
    let client = midir::MidiOutput::new(super::controller::port::CLIENT).ok()?;
    match client.connect(&found, "midi-out") {
        Ok(connection) => {
            log::info!("MIDI out: {name} connected");
            Some((name, connection))
        }
        Err(e) => {
            log::warn!("MIDI out: cannot open {name}: {e}");
            None
        }
    }
}

/// A binary built without the `midi` feature sends nothing.
#[cfg(not(feature = "midi"))]
fn run(_port: &str, _clock: bool, _mtc: Option<Rate>, messages: &Receiver<Vec<u8>>, shared: &Shared) {
    log::info!("{}", super::midi::NOT_BUILT_IN);
    while !shared.stop.load(Ordering::Relaxed) {
        while messages.try_recv().is_ok() {}
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[cfg(all(test, feature = "midi"))]
mod tests {
    use super::*;

    /// Frames at 60 Hz reporting the beat of their step, each late by a render time that
    /// varies from 0 to 40 ms; the thread wakes every millisecond.
    #[test]
    fn the_clock_keeps_the_tempo_through_late_reports_and_jumps_at_a_seek() {
        let bpm = 150.0;
        let start = Instant::now();
        let mut clock = ClockFollower::default();
        let (mut pulses, mut starts, mut burst) = (0, 0, 0);
        let mut report = (TempoClock { bpm, beats: 0.0 }, start);
        for ms in 0..10_000u64 {
            let now = start + Duration::from_millis(ms);
            if ms % 16 == 0 {
                let late = (ms * 7919 % 41) as f64 / 1000.0;
                let beats = (ms as f64 / 1000.0 - late).max(0.0) * bpm / 60.0;
                report = (TempoClock { bpm, beats }, now);
            }
            let (started, sent) = clock.advance(report.0, report.1, now);
            starts += usize::from(started);
            pulses += sent;
            burst = burst.max(sent);
        }
        // 10 s at 150 BPM: 25 beats, 600 pulses (less the lateness at the end, at most a few).
        assert_eq!(starts, 1);
        assert!((590..=601).contains(&pulses), "{pulses} pulses");
        assert!(burst <= 2, "a burst of {burst} pulses");
        // A seek ten beats back: no burst, and pulses go on from there.
        let now = start + Duration::from_millis(10_001);
        let (_, sent) = clock.advance(TempoClock { bpm, beats: 15.0 }, now, now);
        assert_eq!(sent, 0);
        let later = now + Duration::from_millis(100);
        let (_, sent) = clock.advance(TempoClock { bpm, beats: 15.0 }, now, later);
        assert!((5..=7).contains(&sent), "{sent} pulses in 100 ms after the seek");
    }
}
