//! Everything live control needs for one running scene, polled once per frame: OSC and MIDI
//! in, presets, OSC feedback out, the OSCQuery tree, and the control-stream recorder. A source
//! that cannot start (port in use, no MIDI system) is reported once and the show goes on.

use std::path::PathBuf;
use std::time::SystemTime;

use super::audio::sound::{LiveSound, open_audio};
use super::audio::{AudioFrame, AudioLearn, AudioMapper};
use super::controller::Controllers;
use super::feedback::{OscFeedback, ParamChanges};
use super::ltc_out::LtcOut;
use super::midi::{LearnStore, MidiEvent, MidiInput, MidiMapper, MidiParser};
use super::midi_out::MidiOut;
use super::osc::OscReceiver;
use super::osc_route::{OscRouter, RecordRequest, Routed};
use super::oscquery::OscQueryServer;
use super::presets::{PresetFile, PresetStore};
use super::record::Recorder;
use super::site::SiteRules;
use super::tempo::TempoInput;
use super::timecode_in::TimecodeIn;
use super::web::WebOptions;
use crate::params::{ControlEvent, Remap, ShowCommand, Target};
use crate::scene::{AudioSource, Scene, SceneView};

/// Which control sources to open.
#[derive(Clone, Debug)]
pub struct ControlOptions {
    /// OSC listen address (`None`: no OSC input).
    pub osc: Option<String>,
    /// OSC feedback destination `host:port`.
    pub osc_out: Option<String>,
    /// OSCQuery HTTP listen address.
    pub oscquery: Option<String>,
    /// The browser control surface (served with OSCQuery at its address, which replaces
    /// `oscquery`'s).
    pub web: Option<WebOptions>,
    /// Open MIDI inputs.
    pub midi: bool,
    /// Only MIDI ports whose name contains this.
    pub midi_filter: Option<String>,
    /// The controller profile to use (a bundled one's name, or a file); `None`: every bundled
    /// profile and the user's, picked by port name.
    pub controller: Option<String>,
    /// The user's folder of controller profiles.
    pub controllers_dir: PathBuf,
    /// MIDI out to the first port whose name contains this: mapped parameters mirrored.
    pub midi_out: Option<String>,
    /// MIDI clock out (on the `midi_out` port) at the show's tempo.
    pub midi_clock: bool,
    /// MTC out (on the `midi_out` port) at this rate, for the show's position.
    pub mtc_out: Option<crate::timecode::Rate>,
    /// LTC out at this rate on the audio output (`audio_out`'s, else the default).
    pub ltc_out: Option<crate::timecode::Rate>,
    /// The first audio output whose name contains this, for `ltc_out`.
    pub audio_out: Option<String>,
    /// Chase a timecode (MTC from the MIDI inputs or LTC from the audio input), with these
    /// settings over the show's.
    pub chase_in: Option<super::timecode_in::ChaseInput>,
    /// Record the control stream to this file.
    pub record: Option<PathBuf>,
    /// Folder of presets.
    pub presets_dir: PathBuf,
    /// File of learned MIDI mappings.
    pub learn_file: PathBuf,
    /// File of audio mappings learned from the panel.
    pub audio_learn_file: PathBuf,
    /// Audio input: `None` none; `Some(None)` the default device when the scene maps audio;
    /// `Some(Some(name))` the first device whose name contains `name`, always.
    pub audio_in: Option<Option<String>>,
    /// Join the Ableton Link session (builds with the `link` feature).
    pub link: bool,
    /// Host names and third-party origins the OSCQuery server answers beyond its own.
    pub sites: SiteRules,
    /// DMX in from a lighting desk, as this file says (`None`: no DMX in).
    pub dmx_in: Option<PathBuf>,
}

impl Default for ControlOptions {
    fn default() -> Self {
        Self {
            osc: Some("127.0.0.1:9000".into()),
            osc_out: None,
            oscquery: None,
            web: None,
            midi: true,
            midi_filter: None,
            controller: None,
            controllers_dir: "controllers".into(),
            midi_out: None,
            midi_clock: false,
            mtc_out: None,
            ltc_out: None,
            audio_out: None,
            chase_in: None,
            record: None,
            presets_dir: "presets".into(),
            learn_file: "midi-learn.ron".into(),
            audio_learn_file: "audio-learn.ron".into(),
            audio_in: Some(None),
            link: false,
            sites: SiteRules::default(),
            dmx_in: None,
        }
    }
}

/// The live control of one running scene.
pub struct ControlHub {
    /// OSC input, if open.
    pub osc: Option<OscReceiver>,
    router: OscRouter,
    feedback: Option<OscFeedback>,
    /// What changed since the last frame, for feedback and OSCQuery LISTEN.
    changes: ParamChanges,
    /// OSCQuery server, if open.
    pub oscquery: Option<OscQueryServer>,
    /// The browser surface's URLs (with the token), when it is served.
    pub web_urls: Vec<String>,
    midi: Option<MidiInput>,
    parser: MidiParser,
    /// The timecode the timeline chases, when asked for.
    chase: Option<TimecodeIn>,
    /// Pad controllers with profiles, when MIDI is on.
    controllers: Option<Controllers>,
    /// LTC out, when asked for.
    ltc_out: Option<LtcOut>,
    /// MIDI out (mirrored mappings, clock), when asked for.
    midi_out: Option<MidiOut>,
    /// MIDI mappings, learn state and clock.
    pub mapper: MidiMapper,
    learn: LearnStore,
    /// The preset folder.
    pub presets: PresetStore,
    recorder: Option<Recorder>,
    /// Things to tell the performer (shown in the overlay, logged once there).
    pub notices: Vec<String>,
    /// Video recording starts and stops asked for over OSC, for the window to act on.
    pub record_requests: Vec<RecordRequest>,
    /// Tap tempo and the MIDI clock follower.
    tempo: TempoInput,
    /// Live audio and its analysis, when an input is open.
    audio: Option<LiveSound>,
    /// Which audio input to open (see [`ControlOptions::audio_in`]), kept to open it when a
    /// mapping is learned.
    audio_wanted: Option<Option<String>>,
    /// The scene's audio mappings and the learned ones.
    audio_mapper: AudioMapper,
    /// Audio mappings learned from the panel.
    audio_learn: AudioLearn,
    /// The last analysed audio frame (the panel's meter and spectrum).
    pub audio_frame: Option<AudioFrame>,
    /// The Ableton Link session, when joined.
    #[cfg(feature = "link")]
    link: Option<super::link::LinkInput>,
    frame_count: u64,
    /// Preset names, re-read on save and every [`PRESET_RESCAN_FRAMES`] frames (not per frame:
    /// the panel shows them every frame).
    preset_names: Vec<String>,
    /// A recall waiting for its effect chain edits: name, preset, morph seconds.
    pending_recall: Option<(String, PresetFile, f64)>,
    /// DMX in, when a file asks for it.
    pub dmx: Option<super::dmx_in::DmxControl>,
}

/// Frames between re-reads of the preset folder (files may be copied in by hand).
const PRESET_RESCAN_FRAMES: u64 = 60;

impl ControlHub {
    /// Opens what `options` asks for against `scene`.
    pub fn start(options: &ControlOptions, scene: &Scene) -> Self {
        let mut notices = Vec::new();
        let mut report = |r: Result<(), String>| {
            if let Err(e) = r {
                log::warn!("{e}");
                notices.push(e);
            }
        };
        let mut osc = options.osc.as_deref().and_then(|a| OscReceiver::bind(a).map_err(|e| report(Err(e))).ok());
        let feedback =
            options.osc_out.as_deref().and_then(|a| OscFeedback::connect(a).map_err(|e| report(Err(e))).ok());
        let osc_port = osc.as_ref().map_or(0, |o| o.local_addr().port());
        // The browser's writes are OSC too: with UDP input off they still need the queue.
        let surface = options.web.as_ref().map(|web| {
            let inlet = osc.get_or_insert_with(OscReceiver::without_socket).inlet();
            (web.clone(), inlet)
        });
        let query_addr = options.web.as_ref().map(|w| w.addr.as_str()).or(options.oscquery.as_deref());
        let oscquery = query_addr.and_then(|a| {
            OscQueryServer::start_with(a, osc_port, surface, &options.sites).map_err(|e| report(Err(e))).ok()
        });
        let served = options.web.as_ref().zip(oscquery.as_ref());
        let web_urls = served.map(|(web, server)| super::web::announce(server.local_addr(), web)).unwrap_or_default();
        let controllers =
            options.midi.then(|| Controllers::start(options.controller.as_deref(), &options.controllers_dir));
        let controllers = controllers.and_then(|c| {
            // A profile named on the command line that cannot be read is the performer's to know.
            c.map_err(|e| if options.controller.is_some() { report(Err(e)) } else { log::info!("{e}") }).ok()
        });
        // Ports a controller profile serves are the controller thread's; the lights it sends (its
        // own client's ports) are not input.
        let exclude = |name: &str| {
            name.contains(super::controller::port::CLIENT) || controllers.as_ref().is_some_and(|c| c.serves(name))
        };
        let midi = options.midi.then(|| MidiInput::open(options.midi_filter.as_deref(), &exclude));
        let midi = midi.and_then(|m| m.map_err(|e| log::info!("{e}")).ok());
        let midi_out = options.midi_out.as_deref().and_then(|port| {
            MidiOut::start(port, options.midi_clock, options.mtc_out).map_err(|e| report(Err(e))).ok()
        });
        let ltc_out = options
            .ltc_out
            .and_then(|rate| LtcOut::open(options.audio_out.as_deref(), rate).map_err(|e| report(Err(e))).ok());
        let recorder = options.record.as_deref().and_then(|p| Recorder::create(p).map_err(|e| report(Err(e))).ok());
        let learn = LearnStore { path: options.learn_file.clone() };
        let mapper = MidiMapper::new(scene, &learn.load());
        let presets = PresetStore { dir: options.presets_dir.clone() };
        let preset_names = presets.names();
        let (audio_learn, problem) = AudioLearn::load(options.audio_learn_file.clone());
        notices.extend(problem);
        let audio_mapper = AudioMapper::with_learned(scene, audio_learn.bound(scene));
        let code = options.chase_in.and_then(|c| c.ltc_channel());
        let audio = open_audio(options.audio_in.as_ref(), !audio_mapper.is_empty(), code, &mut notices);
        let dmx = options.dmx_in.as_deref().and_then(|path| {
            let started = super::dmx_in::DmxInFile::load(path).and_then(|file| {
                let learned = options.learn_file.with_file_name("dmx-learn.ron");
                super::dmx_in::DmxControl::start(file, Some(learned), scene, &mut notices)
            });
            started.map_err(|e| notices.push(format!("no DMX in: {e}"))).ok()
        });
        #[cfg(feature = "link")]
        let link = options.link.then(|| super::link::LinkInput::join(scene.bpm));
        #[cfg(not(feature = "link"))]
        if options.link {
            let message = "this build has no Ableton Link: build with `--features link` (GPL-2.0-or-later)";
            log::warn!("{message}");
            notices.push(message.into());
        }
        Self {
            osc,
            router: OscRouter::new(scene),
            feedback,
            changes: ParamChanges::default(),
            oscquery,
            web_urls,
            midi,
            parser: MidiParser::default(),
            chase: options.chase_in.map(|c| TimecodeIn::new(c, scene)),
            controllers,
            midi_out,
            ltc_out,
            mapper,
            learn,
            presets,
            recorder,
            notices,
            record_requests: Vec::new(),
            tempo: TempoInput::default(),
            audio,
            audio_wanted: options.audio_in.clone(),
            audio_mapper,
            audio_learn,
            audio_frame: None,
            #[cfg(feature = "link")]
            link,
            frame_count: 0,
            preset_names,
            pending_recall: None,
            dmx,
        }
    }

    /// Rebuilds address and MIDI maps after the scene changed (learned mappings stay, by name).
    /// A parameter waiting for MIDI learn follows `remap` to its new place, or stops waiting if
    /// it left the scene.
    pub fn set_scene(&mut self, scene: &Scene, remap: Option<&Remap>) {
        self.router = OscRouter::new(scene);
        self.rebuild_audio(scene);
        if let Some(chase) = self.chase.as_mut() {
            chase.set_scene(scene);
        }
        if let Some(dmx) = self.dmx.as_mut() {
            dmx.set_scene(scene, &mut self.notices);
        }
        let learning = self.mapper.learning.take();
        self.mapper = MidiMapper::new(scene, &self.learn.load());
        self.mapper.learning = learning.and_then(|t| match remap {
            Some(remap) => remap.target(t),
            None => scene.nodes.get(t.node).filter(|n| t.param < n.params.decls().len()).map(|_| t),
        });
        // Everything counts as changed: controllers get the new scene's values.
        self.changes.reset();
        if let Some(out) = self.midi_out.as_mut() {
            out.reset();
        }
        if let Some(q) = self.oscquery.as_mut() {
            q.scene_changed();
        }
    }

    /// Everything that arrived since the last frame, as control events, in arrival order per
    /// source (OSC before MIDI). `seconds` is the clock time (for MIDI tempo and morphs).
    pub fn poll(&mut self, instance: SceneView<'_>, seconds: f64) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        let scene = instance.scene;
        let batches = self.osc.as_mut().map(|o| o.drain(SystemTime::now())).unwrap_or_default();
        self.router.begin_frame();
        for batch in batches {
            for msg in &batch.messages {
                let Some(osc) = self.osc.as_ref() else { break };
                for routed in self.router.route_all(msg, scene, osc) {
                    match routed {
                        Routed::Event(e) => events.push(e),
                        Routed::SavePreset(name) => self.save_preset(&name, instance),
                        Routed::RecallPreset(name, s) => events.extend(self.recall(&name, s, scene)),
                        Routed::Record(request) => self.record_requests.push(request),
                        Routed::TapTempo => events.extend(self.tempo.tap()),
                        Routed::Released => {}
                    }
                }
            }
        }
        let messages = self.midi.as_ref().map(MidiInput::drain).unwrap_or_default();
        for (at, bytes) in messages {
            if !self.chase.as_mut().is_some_and(|chase| chase.message(at, &bytes)) {
                events.extend(self.midi_bytes(&bytes, scene, seconds));
            }
        }
        if let Some(polled) = self.controllers.as_mut().map(|c| c.poll(&instance)) {
            events.extend(polled.events);
            events.extend((0..polled.taps).filter_map(|_| self.tempo.tap()));
            for e in polled.unused {
                events.extend(self.midi_event(e, scene, seconds));
            }
        }
        if let Some(chase) = self.chase.as_mut()
            && let Some((samples, rate, first)) = self.audio.as_mut().and_then(LiveSound::code)
        {
            chase.audio(&samples, rate, first);
        }
        if let Some(sound) = self.audio.as_mut()
            && let Some((frame, dt)) = sound.analyse()
        {
            events.extend(self.audio_mapper.events(&frame, dt, scene));
            self.audio_frame = Some(frame);
        }
        if let Some(dmx) = self.dmx.as_mut() {
            events.extend(dmx.events(scene, &mut self.notices));
        }
        // A running MIDI clock sets the show's tempo.
        if self.mapper.clock.playing {
            events.extend(self.tempo.follow_clock(self.mapper.clock.bpm()));
        }
        #[cfg(feature = "link")]
        if let Some(link) = self.link.as_mut() {
            let ahead = f64::from(scene.dt);
            events.extend(link.poll(&instance.tempo, ahead));
        }
        events
    }

    /// Rebuilds the audio mappings (the scene's and the learned ones) and opens the input if
    /// they now need one.
    fn rebuild_audio(&mut self, scene: &Scene) {
        self.audio_mapper = AudioMapper::with_learned(scene, self.audio_learn.bound(scene));
        if self.audio.is_none() && !self.audio_mapper.is_empty() && self.audio_wanted == Some(None) {
            self.audio = open_audio(self.audio_wanted.as_ref(), true, None, &mut self.notices);
        }
    }

    /// Maps audio `source` to `target` (the panel's audio learn) and saves it.
    pub fn learn_audio(&mut self, target: Target, source: AudioSource, instance: SceneView<'_>) {
        let now = instance.params(target.node).target_at(target.param);
        match self.audio_learn.learn(instance.scene, target, source, &now) {
            Ok(()) => self.rebuild_audio(instance.scene),
            Err(e) => self.notice(e),
        }
    }

    /// Removes the learned audio mapping of a parameter and saves the file.
    pub fn unlearn_audio(&mut self, node: usize, param: usize, scene: &Scene) {
        if let Err(e) = self.audio_learn.unlearn(scene, node, param) {
            self.notice(e);
        }
        self.rebuild_audio(scene);
    }

    /// Whether audio moves a parameter (a scene or a learned mapping), and whether it was learned.
    pub fn audio_mapped(&self, node: usize, param: usize) -> (bool, bool) {
        self.audio_mapper.maps(node, param)
    }

    /// A tap of tap tempo now (key T, the panel's button): the event that sets the tempo, from
    /// the second tap on.
    pub fn tap_tempo(&mut self) -> Option<ControlEvent> {
        self.tempo.tap()
    }

    /// Feeds raw MIDI bytes (from a port, or a test) through the parser and mappings.
    pub fn midi_bytes(&mut self, bytes: &[u8], scene: &Scene, seconds: f64) -> Vec<ControlEvent> {
        let parsed = self.parser.feed(bytes);
        parsed.into_iter().flat_map(|e| self.midi_event(e, scene, seconds)).collect()
    }

    /// One MIDI event through the mappings, learn and program changes.
    fn midi_event(&mut self, e: MidiEvent, scene: &Scene, seconds: f64) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        let was_learning = self.mapper.is_learning();
        // The note that is being learned only binds; it triggers from then on.
        if !was_learning {
            let commands = super::midi::cue_commands(e, scene).into_iter().chain(self.mapper.note_commands(e));
            events.extend(commands.map(ControlEvent::Show));
        }
        let (writes, program) = self.mapper.handle(e, scene, seconds);
        events.extend(writes.into_iter().map(ControlEvent::Write));
        if let Some(p) = program
            && let Some(name) = self.preset_names.get(usize::from(p)).cloned()
        {
            events.extend(self.recall(&name, 0.0, scene));
        }
        if was_learning && !self.mapper.is_learning() {
            self.persist_learned(scene);
        }
        events
    }

    /// The events that recall preset `name` over `seconds`: its values' morph; or, where its
    /// effect chains differ from the show's, the chain edits first, the morph then coming from
    /// [`Self::recall_after_chain_edits`] once they are applied (its new effects have no
    /// parameters before). Nothing, with a notice, for a preset that cannot be read.
    pub fn recall(&mut self, name: &str, seconds: f64, scene: &Scene) -> Vec<ControlEvent> {
        let file = match self.presets.read(name) {
            Ok(file) => file,
            Err(e) => {
                self.notice(e);
                return Vec::new();
            }
        };
        let (edits, warnings) = file.chain_edits_for(scene);
        for w in warnings {
            self.notice(w);
        }
        if edits.is_empty() {
            self.pending_recall = None;
            return vec![self.morph_to(name, &file, seconds, scene)];
        }
        self.pending_recall = Some((name.to_string(), file, seconds));
        edits.into_iter().map(ControlEvent::Show).collect()
    }

    /// The morph of a recall that waited for its chain edits, if one waits: call when no edit
    /// waits to be applied, with the scene they made.
    pub fn recall_after_chain_edits(&mut self, scene: &Scene) -> Option<ControlEvent> {
        let (name, file, seconds) = self.pending_recall.take()?;
        Some(self.morph_to(&name, &file, seconds, scene))
    }

    /// The morph to preset `file`'s values in `scene`, telling what does not fit.
    fn morph_to(&mut self, name: &str, file: &PresetFile, seconds: f64, scene: &Scene) -> ControlEvent {
        let (values, warnings) = file.values_for(name, scene);
        for w in warnings {
            self.notice(w);
        }
        ControlEvent::Morph { values, seconds }
    }

    /// Saves the current values as preset `name`.
    pub fn save_preset(&mut self, name: &str, instance: SceneView<'_>) {
        match self.presets.save(name, instance) {
            Ok(path) => log::info!("saved preset {}", path.display()),
            Err(e) => self.notice(e),
        }
        self.rescan_presets();
    }

    /// Re-reads the preset folder's names, and offers them in the OSCQuery tree.
    fn rescan_presets(&mut self) {
        self.preset_names = self.presets.names();
        if let Some(q) = self.oscquery.as_mut() {
            q.set_presets(&self.preset_names);
        }
    }

    /// Preset names in recall order (1–9 keys, MIDI program numbers).
    pub fn preset_names(&self) -> &[String] {
        &self.preset_names
    }

    /// Starts MIDI learn for `target`: the next control moved is bound to it.
    pub fn learn(&mut self, target: Target) {
        self.mapper.learning_command = None;
        self.mapper.learning = Some(target);
    }

    /// Starts MIDI learn for clip `clip` of layer `layer` of a show (from 0): the next note
    /// triggers it from then on, and is saved in the learn file.
    pub fn learn_clip(&mut self, layer: usize, clip: usize) {
        self.learn_command(ShowCommand::Trigger { layer, clip: Some(clip) });
    }

    /// Starts MIDI learn for a show command (a clip trigger, an effect chain edit): the next note
    /// sends it from then on, and is saved in the learn file.
    pub fn learn_command(&mut self, command: ShowCommand) {
        self.mapper.learning = None;
        self.mapper.learning_command = Some(command);
    }

    /// Removes a parameter's MIDI bindings and saves the learn file.
    pub fn unlearn(&mut self, node: usize, param: usize, scene: &Scene) {
        self.mapper.unlearn(node, param);
        self.persist_learned(scene);
    }

    fn persist_learned(&mut self, scene: &Scene) {
        if let Err(e) = self.learn.save(&self.mapper, scene) {
            self.notice(e);
        }
    }

    /// Writes the events applied before `frame` to the recording, if one is open.
    pub fn record(&mut self, frame: u64, events: &[ControlEvent], scene: &Scene) {
        if let Some(r) = self.recorder.as_mut()
            && let Err(e) = r.record(frame, events, scene)
        {
            self.recorder = None;
            self.notice(format!("recording stopped: {e}"));
        }
    }

    /// After a frame at `seconds` of the show: sends changed values to the OSC feedback target,
    /// OSCQuery listeners and MIDI out, and refreshes the OSCQuery tree (every 6th frame: clients
    /// poll far slower than that).
    pub fn after_frame(&mut self, instance: SceneView<'_>, seconds: f64) {
        // The changes are found once, and only when someone receives them.
        let listening = self.oscquery.as_ref().is_some_and(OscQueryServer::listening);
        let changes = if self.feedback.is_some() || listening { self.changes.collect(instance) } else { Vec::new() };
        if let Some(f) = self.feedback.as_ref() {
            f.send(&changes);
        }
        if self.frame_count.is_multiple_of(PRESET_RESCAN_FRAMES) {
            self.rescan_presets();
        }
        if let Some(q) = self.oscquery.as_mut() {
            q.after_frame(instance, self.frame_count.is_multiple_of(6), &changes);
        }
        if let Some(c) = self.controllers.as_ref() {
            c.show(&instance);
        }
        if let Some(out) = self.midi_out.as_mut() {
            out.after_frame(self.mapper.bindings(), &instance, seconds);
        }
        if let Some(out) = self.ltc_out.as_ref() {
            out.report(super::mtc_out::code_seconds(&instance, seconds, out.rate()));
        }
        self.frame_count += 1;
    }

    /// Where the chased timecode puts the timeline at `now`; `None` when the show does not chase.
    pub fn timecode(&self, now: std::time::Instant) -> Option<crate::timecode::chase::Chasing> {
        self.chase.as_ref().map(|chase| chase.at(now))
    }

    /// One line of input counters for the overlay.
    pub fn status(&self) -> String {
        let mut parts = Vec::new();
        if let Some(o) = &self.osc {
            let [packets, _, malformed, unknown, bad, applied, dropped] = o.counters().snapshot();
            parts.push(format!(
                "OSC {}: {packets} packets, {applied} applied, {malformed} malformed, {unknown} unknown address, {bad} bad args, {dropped} dropped",
                o.local_addr()
            ));
        }
        match &self.midi {
            Some(m) if !m.ports.is_empty() => parts.push(format!("MIDI: {}", m.ports.join(", "))),
            _ if !super::midi::BUILT_IN => parts.push("MIDI: not built in (--no-default-features)".into()),
            _ => parts.push("MIDI: none".into()),
        }
        parts.extend(self.controllers.as_ref().and_then(Controllers::status));
        parts.extend(self.midi_out.as_ref().map(MidiOut::status));
        parts.extend(self.ltc_out.as_ref().map(LtcOut::status));
        parts.extend(self.chase.as_ref().map(|chase| chase.status(std::time::Instant::now())));
        if let Some(dropped) = self.oscquery.as_ref().map(OscQueryServer::dropped).filter(|&d| d > 0) {
            parts.push(format!("OSCQuery LISTEN: {dropped} changes dropped (a controller fell behind)"));
        }
        #[cfg(feature = "link")]
        if let Some(link) = &self.link {
            parts.push(format!("Link: {} peers", link.peers()));
        }
        if let Some(bpm) = self.mapper.clock.bpm() {
            parts.push(format!("clock {bpm:.1} BPM{}", if self.mapper.clock.playing { " ▶" } else { "" }));
        }
        parts.join(" · ")
    }

    fn notice(&mut self, message: String) {
        log::warn!("{message}");
        self.notices.push(message);
    }
}
