use super::*;
use crate::scene::show::{Clip, Cue, Layer};

fn clip(id: &str, layer: usize, policy: ClipPolicy, transition: Transition) -> Clip {
    Clip { id: id.into(), scene: id.into(), layer, nodes: 0..0, output: None, policy, transition, note: None }
}

fn fade(seconds: f64, quantize: Quantize) -> Transition {
    Transition { kind: Some(0), length: Length::Seconds(seconds), quantize }
}

/// Two layers: a, b on the first (a starts), c on the second.
fn show(transition: Transition, cues: Vec<Cue>) -> Show {
    Show {
        layers: vec![
            Layer { name: "one".into(), node: 3, clips: vec![0, 1], start: Some(0), effects: Vec::new() },
            Layer { name: "two".into(), node: 4, clips: vec![2], start: None, effects: Vec::new() },
        ],
        clips: vec![
            clip("a", 0, ClipPolicy::Restart, transition),
            clip("b", 0, ClipPolicy::Restart, transition),
            clip("c", 1, ClipPolicy::Continue, transition),
        ],
        columns: vec!["first".into(), "second".into()],
        cues,
        loop_cues: true,
        cue_notes: Default::default(),
        master: 5,
        master_effects: Vec::new(),
        effects: Vec::new(),
        mix_kind: None,
        file: None,
        kinds: vec!["crossfade".into()],
        sources: Vec::new(),
        broken: Vec::new(),
        timeline: Default::default(),
    }
}

/// 120 bpm at 60 steps a second: a beat every 30 frames.
fn clock(frame: u64) -> Clock {
    let seconds = frame as f64 / 60.0;
    Clock { frame, seconds, beats: seconds * 2.0 }
}

#[test]
fn a_crossfade_runs_from_the_old_clip_to_the_new_over_its_length() {
    let show = show(fade(1.0, Quantize::Off), Vec::new());
    let mut state = ShowState::new(&show);
    assert_eq!(state.step(&show, clock(0)).started, [0]);
    state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(1) }).unwrap();
    let changes = state.step(&show, clock(10));
    assert_eq!(changes.started, [1]);
    assert!(changes.hidden.is_empty());
    assert_eq!(state.view(0), LayerView { from: Some(0), to: Some(1), progress: 0.0, kind: Some(0), seconds: 0.0 });
    state.step(&show, clock(40));
    assert!((state.view(0).progress - 0.5).abs() < 1e-6);
    assert!(state.visible(0) && state.visible(1));
    let changes = state.step(&show, clock(70));
    assert_eq!(changes.hidden, [0], "the outgoing clip is hidden when the fade ends");
    assert!(!state.view(0).fading());
}

#[test]
fn a_quantized_trigger_waits_for_the_next_beat_or_bar() {
    for (quantize, lands) in [(Quantize::Beat, 30), (Quantize::Bar, 120)] {
        let show = show(fade(0.5, quantize), Vec::new());
        let mut state = ShowState::new(&show);
        state.step(&show, clock(0));
        state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(1) }).unwrap();
        let mut started_at = None;
        for frame in 7..200 {
            if state.step(&show, clock(frame)).started == [1] {
                started_at = Some(frame);
                break;
            }
            assert!(state.waiting(0), "{quantize:?} frame {frame}");
        }
        assert_eq!(started_at, Some(lands), "{quantize:?}");
    }
}

#[test]
fn a_trigger_on_the_beat_starts_at_once() {
    let show = show(fade(0.5, Quantize::Beat), Vec::new());
    let mut state = ShowState::new(&show);
    state.step(&show, clock(0));
    state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(1) }).unwrap();
    assert_eq!(state.step(&show, clock(60)).started, [1]);
}

#[test]
fn retriggering_the_playing_restart_clip_restarts_it_with_a_cut() {
    let show = show(fade(1.0, Quantize::Off), Vec::new());
    let mut state = ShowState::new(&show);
    state.step(&show, clock(0));
    state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(0) }).unwrap();
    assert_eq!(state.step(&show, clock(90)).started, [0]);
    assert_eq!(state.started(0), 90);
    assert!(!state.view(0).fading());
}

#[test]
fn cues_hold_then_go_on_and_loop() {
    let cue = |clips: Vec<(usize, Option<usize>)>, hold| Cue {
        name: String::new(),
        column: None,
        clips,
        transition: Some(Transition { kind: None, length: Length::Seconds(0.0), quantize: Quantize::Off }),
        hold,
    };
    let cues = vec![
        cue(vec![(0, Some(1))], Some(Length::Seconds(1.0))),
        cue(vec![(1, Some(0)), (0, None)], Some(Length::Beats(1.0))),
    ];
    let show = show(fade(1.0, Quantize::Off), cues);
    let mut state = ShowState::new(&show);
    state.step(&show, clock(0));
    assert_eq!((state.cue(), state.playing(0)), (Some(0), Some(1)));
    state.step(&show, clock(59));
    assert_eq!(state.cue(), Some(0));
    let changes = state.step(&show, clock(60));
    assert_eq!((state.cue(), state.playing(0), state.playing(1)), (Some(1), None, Some(2)));
    assert_eq!(changes.hidden, [1]);
    state.step(&show, clock(90));
    assert_eq!(state.cue(), Some(0), "after the last cue the list loops");
    state.request(&show, ShowCommand::CueGoto(1)).unwrap();
    state.request(&show, ShowCommand::CueBack).unwrap();
    state.step(&show, clock(91));
    assert_eq!(state.cue(), Some(0));
}

#[test]
fn a_column_triggers_one_clip_per_layer_and_bad_numbers_are_refused() {
    let show = show(Transition { kind: None, length: Length::Seconds(0.0), quantize: Quantize::Off }, Vec::new());
    let mut state = ShowState::new(&show);
    state.step(&show, clock(0));
    state.request(&show, ShowCommand::Column(0)).unwrap();
    state.step(&show, clock(1));
    assert_eq!((state.playing(0), state.playing(1)), (Some(0), Some(2)));
    assert!(state.request(&show, ShowCommand::Column(2)).is_err());
    assert!(state.request(&show, ShowCommand::Trigger { layer: 1, clip: Some(1) }).is_err());
    assert!(state.request(&show, ShowCommand::Trigger { layer: 2, clip: None }).is_err());
    assert!(state.request(&show, ShowCommand::CueGo).is_err(), "no cues");
}

#[test]
fn a_flood_of_triggers_on_a_layer_is_one_switch_to_the_last() {
    let cut = Transition { kind: None, length: Length::Seconds(0.0), quantize: Quantize::Off };
    let show = show(cut, Vec::new());
    let mut state = ShowState::new(&show);
    state.step(&show, clock(0));
    // A 1,000-message bundle retriggering the playing clip: one restart, not a thousand.
    for _ in 0..1000 {
        state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(0) }).unwrap();
    }
    let changes = state.step(&show, clock(1));
    assert_eq!((changes.started, changes.switched.len()), (vec![0], 1));
    // Alternating clips: the last one wins, and the other layer's trigger stays.
    for i in 0..1001 {
        state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(i % 2) }).unwrap();
        if i == 500 {
            state.request(&show, ShowCommand::Trigger { layer: 1, clip: Some(0) }).unwrap();
        }
    }
    let changes = state.step(&show, clock(2));
    assert_eq!(changes.switched, [(1, Some(2)), (0, Some(0))]);
    assert_eq!(changes.started, [0]);
    // A column is its layers' triggers: a later trigger on one layer replaces its part.
    state.request(&show, ShowCommand::Column(0)).unwrap();
    state.request(&show, ShowCommand::Trigger { layer: 0, clip: Some(1) }).unwrap();
    state.step(&show, clock(3));
    assert_eq!((state.playing(0), state.playing(1)), (Some(1), Some(2)));
}

#[test]
fn cue_commands_past_the_cap_in_one_step_are_dropped_and_told() {
    let cue = Cue { name: String::new(), column: None, clips: vec![(0, Some(1))], transition: None, hold: None };
    let show = show(fade(1.0, Quantize::Off), vec![cue.clone(), cue]);
    let mut state = ShowState::new(&show);
    state.step(&show, clock(0));
    for _ in 0..10_000 {
        state.request(&show, ShowCommand::CueGo).unwrap();
    }
    assert_eq!(state.requests.len(), MAX_COMMANDS_PER_STEP);
    let changes = state.step(&show, clock(1));
    let told = format!("{} show commands past {MAX_COMMANDS_PER_STEP}", 10_000 - MAX_COMMANDS_PER_STEP);
    assert!(changes.messages.iter().any(|m| m.starts_with(&told)), "{:?}", changes.messages);
    assert!(state.step(&show, clock(2)).messages.is_empty(), "told once");
}
