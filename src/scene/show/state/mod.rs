//! A show's play state on the fixed clock: which clip each layer plays, the transition running
//! on it, triggers waiting for their beat, and where the cue list stands. Pure CPU and a pure
//! function of the commands and the clock, so a show seeks and replays like a scene.

use super::{ClipPolicy, Length, Quantize, Show, Transition};
use crate::params::ShowCommand;

/// The clock a step runs at: frame, seconds and the tempo's beat position.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Clock {
    /// Frame index.
    pub frame: u64,
    /// Seconds since start.
    pub seconds: f64,
    /// Beats since start on the show's tempo clock.
    pub beats: f64,
}

/// A running transition on a layer.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Fade {
    from: Option<usize>,
    transition: Transition,
    since: Clock,
}

/// One layer's state.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
struct LayerState {
    playing: Option<usize>,
    fade: Option<Fade>,
}

/// A trigger waiting for its beat or bar.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Pending {
    due_beats: f64,
    layer: usize,
    clip: Option<usize>,
    transition: Transition,
}

/// What one step changed, for the scene to act on.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepChanges {
    /// Restart clips that start from their first frame at this step (they need fresh state).
    pub started: Vec<usize>,
    /// Clips shown before this step and not after it.
    pub hidden: Vec<usize>,
    /// Layers whose clip changed at this step, and the clip each plays now.
    pub switched: Vec<(usize, Option<usize>)>,
    /// Things to tell the performer (a GO past the last cue of a show that does not loop).
    pub messages: Vec<String>,
}

/// What a layer shows now: a transition from one clip to another, or one clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerView {
    /// The outgoing clip of a running transition.
    pub from: Option<usize>,
    /// The clip playing (the incoming one during a transition).
    pub to: Option<usize>,
    /// The transition's position 0–1 (1 when none runs).
    pub progress: f32,
    /// The transition shader (index into [`Show::kinds`]) while one runs.
    pub kind: Option<usize>,
    /// Seconds since the transition began.
    pub seconds: f32,
}

impl LayerView {
    /// Whether a transition is being drawn.
    pub fn fading(&self) -> bool {
        self.kind.is_some() && self.progress < 1.0
    }
}

/// The play state of a show.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ShowState {
    layers: Vec<LayerState>,
    pending: Vec<Pending>,
    requests: Vec<ShowCommand>,
    /// Commands dropped since the last step (past [`MAX_COMMANDS_PER_STEP`]).
    dropped: usize,
    cue: Option<usize>,
    cue_since: Clock,
    /// Per clip: the frame its own clock starts at (restart clips; 0 for the others).
    started: Vec<u64>,
    started_once: bool,
    last: Clock,
}

impl ShowState {
    /// Nothing playing yet: the first step starts each layer's start clip and the first cue.
    pub fn new(show: &Show) -> Self {
        Self {
            layers: vec![LayerState::default(); show.layers.len()],
            pending: Vec::new(),
            requests: Vec::new(),
            dropped: 0,
            cue: None,
            cue_since: Clock::default(),
            started: vec![0; show.clips.len()],
            started_once: false,
            last: Clock::default(),
        }
    }

    /// Queues `command` for the next step; a layer, clip, column or cue the show does not have
    /// is refused with the reason.
    pub fn request(&mut self, show: &Show, command: ShowCommand) -> Result<(), String> {
        let ok = match command {
            ShowCommand::Trigger { layer, clip } => {
                layer < show.layers.len() && clip.is_none_or(|c| c < show.layers[layer].clips.len())
            }
            ShowCommand::Column(n) => n < show.columns.len(),
            ShowCommand::CueGoto(n) => n < show.cues.len(),
            ShowCommand::CueGo | ShowCommand::CueBack => !show.cues.is_empty(),
            // A chain edit changes the scene itself: the instance applies it, never the play state.
            ShowCommand::Effect { .. } => return Err(format!("{command:?}: not a play-state command")),
        };
        if !ok {
            return Err(format!("{command:?}: the show has no such layer, clip, column or cue"));
        }
        match command {
            // A column is its layers' triggers, so that they coalesce with the others.
            ShowCommand::Column(n) => {
                for layer in (0..show.layers.len()).filter(|&l| show.clip_at(l, n).is_some()) {
                    self.queue(ShowCommand::Trigger { layer, clip: Some(n) });
                }
            }
            command => self.queue(command),
        }
        Ok(())
    }

    /// Queues `command` for the next step. Of the triggers one layer gets in a step only the
    /// last counts (any earlier one is dropped: the layer would have left it in the same step),
    /// and at most [`MAX_COMMANDS_PER_STEP`] commands wait; the rest are dropped and counted.
    fn queue(&mut self, command: ShowCommand) {
        if let ShowCommand::Trigger { layer, .. } = command {
            self.requests.retain(|r| !matches!(r, ShowCommand::Trigger { layer: l, .. } if *l == layer));
        }
        if self.requests.len() < MAX_COMMANDS_PER_STEP {
            self.requests.push(command);
        } else {
            self.dropped += 1;
        }
    }

    /// The current cue, if one has gone.
    pub fn cue(&self) -> Option<usize> {
        self.cue
    }

    /// The clip layer `layer` plays (the incoming one during a transition).
    pub fn playing(&self, layer: usize) -> Option<usize> {
        self.layers.get(layer).and_then(|l| l.playing)
    }

    /// Whether clip `clip` is drawn now (playing, or the outgoing side of a transition).
    pub fn visible(&self, clip: usize) -> bool {
        self.layers.iter().any(|l| l.playing == Some(clip) || l.fade.is_some_and(|f| f.from == Some(clip)))
    }

    /// Whether this state can be `show`'s (a checkpoint's is checked before it is taken): one
    /// entry per layer and clip, and every clip, layer, cue and transition one the show has.
    pub fn fits(&self, show: &Show) -> bool {
        let clip = |c: Option<usize>| c.is_none_or(|c| c < show.clips.len());
        let transition = |t: &Transition| t.kind.is_none_or(|k| k < show.kinds.len());
        self.layers.len() == show.layers.len()
            && self.started.len() == show.clips.len()
            && self.cue.is_none_or(|c| c < show.cues.len())
            && self
                .layers
                .iter()
                .all(|l| clip(l.playing) && l.fade.is_none_or(|f| clip(f.from) && transition(&f.transition)))
            && self.pending.iter().all(|p| p.layer < show.layers.len() && clip(p.clip) && transition(&p.transition))
    }

    /// Whether a trigger is waiting for its beat on layer `layer`.
    pub fn waiting(&self, layer: usize) -> bool {
        self.pending.iter().any(|p| p.layer == layer)
    }

    /// The beat position of the last step (what its triggers were due against).
    pub fn beats(&self) -> f64 {
        self.last.beats
    }

    /// The clip a trigger waiting on layer `layer` will start (`Some(None)`: it stops the
    /// layer), the last one if several wait.
    pub fn queued(&self, layer: usize) -> Option<Option<usize>> {
        self.pending.iter().rev().find(|p| p.layer == layer).map(|p| p.clip)
    }

    /// The frame clip `clip`'s own clock started at (0 for a clip that continues).
    pub fn started(&self, clip: usize) -> u64 {
        self.started.get(clip).copied().unwrap_or(0)
    }

    /// What layer `layer` shows at the last step.
    pub fn view(&self, layer: usize) -> LayerView {
        let state = self.layers.get(layer).copied().unwrap_or_default();
        match state.fade {
            Some(fade) => {
                let progress = progress(&fade, self.last);
                let seconds = (self.last.seconds - fade.since.seconds) as f32;
                LayerView { from: fade.from, to: state.playing, progress, kind: fade.transition.kind, seconds }
            }
            None => LayerView { from: None, to: state.playing, progress: 1.0, kind: None, seconds: 0.0 },
        }
    }

    /// Runs the show's part of one fixed step at `clock`: the first step's start clips and cue,
    /// queued commands in order, triggers whose beat has come, a cue whose hold is over, and
    /// transitions that ended.
    pub fn step(&mut self, show: &Show, clock: Clock) -> StepChanges {
        let before: Vec<bool> = (0..show.clips.len()).map(|c| self.visible(c)).collect();
        let mut changes = StepChanges::default();
        self.last = clock;
        if !self.started_once {
            self.started_once = true;
            for (l, layer) in show.layers.iter().enumerate() {
                if let Some(c) = layer.start.and_then(|i| layer.clips.get(i)) {
                    let cut = Transition { kind: None, length: Length::Seconds(0.0), quantize: Quantize::Off };
                    self.start(show, l, Some(*c), cut, clock, &mut changes);
                }
            }
            if !show.cues.is_empty() {
                self.go_cue(show, 0, clock, &mut changes);
            }
        }
        if self.dropped > 0 {
            let dropped = std::mem::take(&mut self.dropped);
            changes
                .messages
                .push(format!("{dropped} show commands past {MAX_COMMANDS_PER_STEP} in one frame were dropped"));
        }
        for command in std::mem::take(&mut self.requests) {
            match command {
                ShowCommand::Trigger { layer, clip } => {
                    let clip = clip.and_then(|c| show.clip_at(layer, c));
                    self.trigger(show, layer, clip, None, clock, &mut changes);
                }
                ShowCommand::Column(n) => self.column(show, n, None, clock, &mut changes),
                ShowCommand::CueGo => self.go_next(show, clock, &mut changes),
                ShowCommand::CueBack => {
                    let back = self.cue.map_or(0, |c| c.saturating_sub(1));
                    self.go_cue(show, back, clock, &mut changes);
                }
                ShowCommand::CueGoto(n) => self.go_cue(show, n, clock, &mut changes),
                ShowCommand::Effect { .. } => {}
            }
        }
        let (due, waiting): (Vec<Pending>, Vec<Pending>) =
            self.pending.iter().partition(|p| p.due_beats <= clock.beats + BEAT_EPSILON);
        self.pending = waiting;
        for p in due {
            self.start(show, p.layer, p.clip, p.transition, clock, &mut changes);
        }
        if let Some(hold) = self.cue.and_then(|c| show.cues[c].hold)
            && elapsed(hold, self.cue_since, clock) >= 1.0
        {
            self.go_next(show, clock, &mut changes);
        }
        for layer in &mut self.layers {
            if layer.fade.is_some_and(|f| progress(&f, clock) >= 1.0) {
                layer.fade = None;
            }
        }
        changes.hidden = (0..show.clips.len()).filter(|&c| before[c] && !self.visible(c)).collect();
        // A clip started twice in one step (two cues that retrigger it) needs one fresh copy.
        changes.started.sort_unstable();
        changes.started.dedup();
        changes
    }

    /// Carries the state of an earlier version of the show over to `show` (a hot reload): each
    /// layer keeps playing the clip of the same id, the cue list stays where it is; running
    /// transitions and waiting triggers end.
    pub fn carried(&self, old: &Show, show: &Show) -> ShowState {
        // A chain edit (or a reload that touched only effects or values) plays the same clips
        // on the same layers with the same transitions and cues: everything carries, so a fade
        // runs on and a trigger waiting for its bar still fires.
        if same_playlist(old, show) {
            return self.clone();
        }
        let mut next = ShowState::new(show);
        next.started_once = self.started_once;
        next.last = self.last;
        next.cue = self.cue.filter(|&c| c < show.cues.len());
        next.cue_since = self.cue_since;
        for (c, clip) in old.clips.iter().enumerate() {
            if let Some(n) = show.clips.iter().position(|k| k.id == clip.id) {
                next.started[n] = self.started[c];
            }
        }
        for (l, state) in self.layers.iter().enumerate().take(show.layers.len()) {
            let id = state.playing.map(|c| old.clips[c].id.as_str());
            next.layers[l].playing =
                show.layers[l].clips.iter().copied().find(|&c| Some(show.clips[c].id.as_str()) == id);
        }
        next
    }

    fn go_next(&mut self, show: &Show, clock: Clock, changes: &mut StepChanges) {
        let next = self.cue.map_or(0, |c| c + 1);
        if next < show.cues.len() {
            self.go_cue(show, next, clock, changes);
        } else if show.loop_cues {
            self.go_cue(show, 0, clock, changes);
        } else {
            changes.messages.push("GO: this was the last cue (the show does not loop)".into());
        }
    }

    fn go_cue(&mut self, show: &Show, n: usize, clock: Clock, changes: &mut StepChanges) {
        let Some(cue) = show.cues.get(n) else { return };
        self.cue = Some(n);
        self.cue_since = clock;
        if let Some(column) = cue.column {
            self.column(show, column, cue.transition, clock, changes);
        }
        for &(layer, clip) in &cue.clips {
            let clip = clip.and_then(|c| show.clip_at(layer, c));
            self.trigger(show, layer, clip, cue.transition, clock, changes);
        }
    }

    fn column(
        &mut self,
        show: &Show,
        n: usize,
        transition: Option<Transition>,
        clock: Clock,
        changes: &mut StepChanges,
    ) {
        for l in 0..show.layers.len() {
            if let Some(c) = show.clip_at(l, n) {
                self.trigger(show, l, Some(c), transition, clock, changes);
            }
        }
    }

    /// Triggers `clip` (an index into the show's clips; `None` empties the layer) on `layer`,
    /// now or at its beat.
    fn trigger(
        &mut self,
        show: &Show,
        layer: usize,
        clip: Option<usize>,
        transition: Option<Transition>,
        clock: Clock,
        changes: &mut StepChanges,
    ) {
        // The clip's own transition; emptying a layer fades out as its playing clip would.
        let own = clip.or(self.playing(layer)).map(|c| show.clips[c].transition);
        let Some(transition) = transition.or(own) else { return };
        self.pending.retain(|p| p.layer != layer);
        let due = match transition.quantize {
            Quantize::Off => None,
            Quantize::Beat => Some(next_multiple(clock.beats, 1.0)),
            Quantize::Bar => Some(next_multiple(clock.beats, BEATS_PER_BAR)),
        };
        match due {
            Some(due_beats) if due_beats > clock.beats + BEAT_EPSILON => {
                self.pending.push(Pending { due_beats, layer, clip, transition });
            }
            _ => self.start(show, layer, clip, transition, clock, changes),
        }
    }

    fn start(
        &mut self,
        show: &Show,
        layer: usize,
        clip: Option<usize>,
        transition: Transition,
        clock: Clock,
        changes: &mut StepChanges,
    ) {
        let state = &mut self.layers[layer];
        let restarts = clip.filter(|&c| show.clips[c].policy == ClipPolicy::Restart);
        if state.playing == clip {
            // Retriggering the playing clip restarts it (a cut: one clip cannot show twice).
            if let Some(c) = restarts {
                state.fade = None;
                self.started[c] = clock.frame;
                changes.started.push(c);
                changes.switched.push((layer, clip));
            }
            return;
        }
        changes.switched.push((layer, clip));
        let instant =
            transition.kind.is_none() || matches!(transition.length, Length::Seconds(x) | Length::Beats(x) if x <= 0.0);
        state.fade = (!instant).then_some(Fade { from: state.playing, transition, since: clock });
        state.playing = clip;
        if let Some(c) = restarts {
            self.started[c] = clock.frame;
            changes.started.push(c);
        }
    }
}

/// Show commands one step takes at most, after triggers coalesce per layer: a flood of cue
/// commands past it is dropped, not queued.
pub const MAX_COMMANDS_PER_STEP: usize = 64;

/// Beats in a bar (4/4, as Ableton Link's default quantum).
pub const BEATS_PER_BAR: f64 = 4.0;

/// Beat positions this close count as equal (the tempo clock sums f64 steps).
const BEAT_EPSILON: f64 = 1e-6;

/// The first multiple of `unit` at or after `beats`.
fn next_multiple(beats: f64, unit: f64) -> f64 {
    let n = (beats / unit - BEAT_EPSILON).ceil();
    n * unit
}

/// How far through `length` the time since `since` is (1 or more: done).
fn elapsed(length: Length, since: Clock, now: Clock) -> f64 {
    match length {
        Length::Seconds(s) if s > 0.0 => (now.seconds - since.seconds) / s,
        Length::Beats(b) if b > 0.0 => (now.beats - since.beats) / b,
        _ => 1.0,
    }
}

fn progress(fade: &Fade, now: Clock) -> f32 {
    elapsed(fade.transition.length, fade.since, now).clamp(0.0, 1.0) as f32
}

/// Whether shows `a` and `b` have the same clips (by id, in order), layers (by their clips),
/// transition kinds and cues: indices into any of them mean the same in both.
fn same_playlist(a: &Show, b: &Show) -> bool {
    a.kinds == b.kinds
        && a.clips.len() == b.clips.len()
        && a.clips.iter().zip(&b.clips).all(|(x, y)| x.id == y.id && x.layer == y.layer && x.transition == y.transition)
        && a.layers.len() == b.layers.len()
        && a.layers.iter().zip(&b.layers).all(|(x, y)| x.clips == y.clips && x.start == y.start)
        && a.cues == b.cues
}

#[cfg(test)]
mod tests;
