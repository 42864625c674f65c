//! Controllers' MIDI ports, on a thread of their own: it finds the ports each profile serves,
//! connects (again after an unplug), sends the profile's mode SysEx once per connection, and
//! sends the lights that changed, at most the profile's rate. The render thread only offers
//! the newest lights (never waiting for the lock) and drains what came in.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::profile::{Control, Profile};

/// Messages from controllers held for the render thread at most (a few seconds of a busy
/// controller); past that they are dropped and counted.
const INPUT_QUEUE: usize = 4096;
/// How often the thread looks for ports that appeared or went.
const SCAN_EVERY: Duration = Duration::from_millis(500);
/// How often the thread sends lights.
const TICK: Duration = Duration::from_millis(5);
/// How long after a connection the mode SysEx goes (a port just connected may not carry the
/// first message yet: JACK's did not, one time in three), and the lights after it (a device
/// switching mode may miss them).
const SETTLE: Duration = Duration::from_millis(100);

/// The MIDI client name of the controllers' connections (other MIDI input leaves its ports).
pub const CLIENT: &str = "indra-controller";

/// The lights a profile's controller should show: (control, message).
pub type Lights = Vec<(Control, [u8; 3])>;

/// What the thread shares with the render thread.
#[derive(Default)]
struct Shared {
    /// Per profile: the newest lights offered.
    lights: Vec<Mutex<Option<Lights>>>,
    /// Per profile: whether its controller's output is connected.
    connected: Vec<AtomicBool>,
    /// Messages sent to controllers.
    sent: AtomicU64,
    /// Offers the render thread could not leave (the thread held the lock).
    missed: AtomicU64,
    /// Incoming messages dropped on a full queue.
    dropped: AtomicU64,
    stop: AtomicBool,
}

/// The controllers' ports: the thread and what it shares.
pub struct ControllerPorts {
    shared: Arc<Shared>,
    input: Receiver<(usize, Vec<u8>)>,
    thread: Option<JoinHandle<()>>,
}

impl ControllerPorts {
    /// Starts watching for the ports `profiles` serve.
    pub fn start(profiles: Vec<Profile>) -> Result<Self, String> {
        let shared = Arc::new(Shared {
            lights: profiles.iter().map(|_| Mutex::new(None)).collect(),
            connected: profiles.iter().map(|_| AtomicBool::new(false)).collect(),
            ..Default::default()
        });
        let (tx, input) = sync_channel(INPUT_QUEUE);
        let thread_shared = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("indra-controllers".into())
            .spawn(move || watch(profiles, thread_shared, tx))
            .map_err(|e| format!("cannot start the controller thread: {e}"))?;
        Ok(Self { shared, input, thread: Some(thread) })
    }

    /// Every message received since the last call: (profile index, bytes).
    pub fn drain(&self) -> Vec<(usize, Vec<u8>)> {
        self.input.try_iter().collect()
    }

    /// Whether profile `i`'s controller is connected (its output port).
    pub fn connected(&self, i: usize) -> bool {
        self.shared.connected.get(i).is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Offers profile `i`'s lights; never waits (a busy lock skips this offer, and counts it).
    pub fn offer(&self, i: usize, lights: Lights) {
        match self.shared.lights.get(i).map(Mutex::try_lock) {
            Some(Ok(mut slot)) => *slot = Some(lights),
            _ => drop(self.shared.missed.fetch_add(1, Ordering::Relaxed)),
        }
    }

    /// Messages sent, offers missed, incoming messages dropped.
    pub fn counts(&self) -> (u64, u64, u64) {
        let s = &self.shared;
        (s.sent.load(Ordering::Relaxed), s.missed.load(Ordering::Relaxed), s.dropped.load(Ordering::Relaxed))
    }
}

impl Drop for ControllerPorts {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// One profile's connections and what its controller shows.
#[derive(Default)]
struct Session {
    input: Option<(String, midir::MidiInputConnection<()>)>,
    output: Option<(String, midir::MidiOutputConnection)>,
    /// The newest lights offered (kept: those the budget held back go at a later tick).
    wanted: Lights,
    /// The message last sent per control.
    shown: std::collections::HashMap<Control, [u8; 3]>,
    /// Messages it may send now (refilled at the profile's rate, at most a second's worth).
    budget: f64,
    /// When the output connected, until the mode SysEx has gone.
    hello_from: Option<Instant>,
    /// When lights may go.
    lights_from: Option<Instant>,
}

/// The thread: scans ports, keeps sessions connected, sends lights.
fn watch(profiles: Vec<Profile>, shared: Arc<Shared>, tx: SyncSender<(usize, Vec<u8>)>) {
    let mut sessions: Vec<Session> = profiles.iter().map(|_| Session::default()).collect();
    let mut probes: Option<(midir::MidiInput, midir::MidiOutput)> = None;
    let mut last_scan: Option<Instant> = None;
    let mut last_tick = Instant::now();
    let mut told = false;
    while !shared.stop.load(Ordering::Relaxed) {
        if last_scan.is_none_or(|t| t.elapsed() >= SCAN_EVERY) {
            last_scan = Some(Instant::now());
            if probes.is_none() {
                probes = open_probes()
                    .map_err(|e| {
                        if !std::mem::replace(&mut told, true) {
                            log::info!("{e}")
                        }
                    })
                    .ok();
            }
            if let Some((inputs, outputs)) = &probes {
                for (i, (profile, session)) in profiles.iter().zip(&mut sessions).enumerate() {
                    session.rescan(i, profile, inputs, outputs, &tx, &shared);
                    shared.connected[i].store(session.output.is_some(), Ordering::Relaxed);
                }
            }
        }
        let elapsed = last_tick.elapsed().as_secs_f64();
        last_tick = Instant::now();
        for (i, (profile, session)) in profiles.iter().zip(&mut sessions).enumerate() {
            let rate = f64::from(profile.rate);
            session.budget = (session.budget + elapsed * rate).min(rate);
            if let Some(offered) = shared.lights[i].lock().ok().and_then(|mut slot| slot.take()) {
                session.wanted = offered;
            }
            session.greet(profile, &shared);
            session.show(&shared);
        }
        std::thread::sleep(TICK);
    }
}

/// The ports a client sees, with their names (those whose name cannot be read are left out).
pub fn named_ports<T: midir::MidiIO>(client: &T) -> Vec<(T::Port, String)> {
    client.ports().into_iter().filter_map(|p| Some((p.clone(), client.port_name(&p).ok()?))).collect()
}

/// Clients that list ports (kept: a JACK client per scan would churn the server).
fn open_probes() -> Result<(midir::MidiInput, midir::MidiOutput), String> {
    let inputs = midir::MidiInput::new("indra-controllers").map_err(|e| format!("no MIDI for controllers ({e})"))?;
    let outputs = midir::MidiOutput::new("indra-controllers").map_err(|e| format!("no MIDI for controllers ({e})"))?;
    Ok((inputs, outputs))
}

impl Session {
    /// Drops connections whose port went; connects to ports the profile serves that appeared.
    fn rescan(
        &mut self,
        i: usize,
        profile: &Profile,
        inputs: &midir::MidiInput,
        outputs: &midir::MidiOutput,
        tx: &SyncSender<(usize, Vec<u8>)>,
        shared: &Arc<Shared>,
    ) {
        let (in_names, out_names) = (named_ports(inputs), named_ports(outputs));
        if let Some((name, connection)) = self.input.take_if(|(name, _)| !in_names.iter().any(|(_, n)| n == name)) {
            connection.close();
            log::info!("controller {}: input {name} went away", profile.name);
        }
        if let Some((name, connection)) = self.output.take_if(|(name, _)| !out_names.iter().any(|(_, n)| n == name)) {
            connection.close();
            log::info!("controller {}: output {name} went away", profile.name);
        }
        if self.input.is_none()
            && let Some((port, name)) = in_names.into_iter().find(|(_, n)| profile.serves(n))
            && let Ok(client) = midir::MidiInput::new(CLIENT)
        {
            let (tx, shared) = (tx.clone(), Arc::clone(shared));
            let forward = move |_: u64, message: &[u8], _: &mut ()| {
                if tx.try_send((i, message.to_vec())).is_err() {
                    shared.dropped.fetch_add(1, Ordering::Relaxed);
                }
            };
            match client.connect(&port, "controller-in", forward, ()) {
                Ok(connection) => {
                    log::info!("controller {}: input {name} connected", profile.name);
                    self.input = Some((name, connection));
                }
                Err(e) => log::warn!("controller {}: cannot open {name}: {e}", profile.name),
            }
        }
        if self.output.is_none()
            && let Some((port, name)) = out_names.into_iter().find(|(_, n)| profile.serves(n))
            && let Ok(client) = midir::MidiOutput::new(CLIENT)
        {
            match client.connect(&port, "controller-out") {
                Ok(connection) => {
                    // A controller that comes back has forgotten its mode and its lights.
                    self.shown.clear();
                    self.hello_from = Some(Instant::now() + SETTLE);
                    self.lights_from = None;
                    log::info!("controller {}: output {name} connected", profile.name);
                    self.output = Some((name, connection));
                }
                Err(e) => log::warn!("controller {}: cannot open {name}: {e}", profile.name),
            }
        }
    }

    /// Sends the profile's mode SysEx once the connection has settled.
    fn greet(&mut self, profile: &Profile, shared: &Shared) {
        let Some((_, output)) = self.output.as_mut() else { return };
        if self.hello_from.is_none_or(|t| Instant::now() < t) {
            return;
        }
        self.hello_from = None;
        if !profile.hello.is_empty() && output.send(&profile.hello).is_ok() {
            shared.sent.fetch_add(1, Ordering::Relaxed);
        }
        self.lights_from = Some(Instant::now() + if profile.hello.is_empty() { Duration::ZERO } else { SETTLE });
    }

    /// Sends the lights that differ from those shown, as many as the budget allows (the rest
    /// go at the next tick: they still differ).
    fn show(&mut self, shared: &Shared) {
        let Some((_, output)) = self.output.as_mut() else { return };
        if self.lights_from.is_none_or(|t| Instant::now() < t) {
            return;
        }
        for (control, message) in &self.wanted {
            if self.budget < 1.0 {
                return;
            }
            if self.shown.get(control) == Some(message) {
                continue;
            }
            if output.send(message).is_ok() {
                self.budget -= 1.0;
                shared.sent.fetch_add(1, Ordering::Relaxed);
                self.shown.insert(*control, *message);
            }
        }
    }
}
