use super::profile::{Action, BUNDLED, Control, FaderTarget, Light, Profile, choose};
use super::surface::{PadState, Surface};
use crate::control::midi::MidiEvent;
use crate::params::{ControlEvent, ParamSet, ParamValue, ShowCommand, TempoClock};
use crate::scene::show::{Clock, ShowState};
use crate::scene::{Scene, SceneView};

fn bundled(name: &str) -> Profile {
    let (file, text) = BUNDLED.iter().find(|(f, _)| f.starts_with(name)).unwrap();
    Profile::parse(text, file).unwrap()
}

fn button(p: &Profile, action: Action) -> Control {
    p.buttons.iter().find(|b| b.action == action && !b.shifted).unwrap().control
}

fn fader(p: &Profile, target: FaderTarget) -> Control {
    p.faders.iter().find(|f| f.target == target).unwrap().control
}

#[test]
fn every_bundled_profile_parses_and_keeps_its_rules() {
    for (file, text) in BUNDLED {
        let p = Profile::parse(text, file).unwrap_or_else(|e| panic!("{e}"));
        assert!(p.grid.pads().count() >= 16, "{file}");
        assert!(p.ports.iter().all(|port| p.serves(port)), "{file}");
    }
    assert_eq!(choose(Some("launchpad-x"), std::path::Path::new("/nonexistent")).unwrap()[0].name, "Launchpad X");
    assert_eq!(choose(Some("APC mini mk2"), std::path::Path::new("/nonexistent")).unwrap()[0].name, "APC mini mk2");
    let e = choose(Some("apc20"), std::path::Path::new("/nonexistent")).unwrap_err();
    assert!(e.contains("no controller profile 'apc20'") && e.contains("launchpad-mini-mk3"), "{e}");
}

/// The numbers of each vendor's published protocol (cited in each profile's comments).
#[test]
fn profiles_follow_the_vendors_protocols() {
    // Akai, "APC mini mk2 Communication Protocol" v1.0.
    let p = bundled("apc-mini-mk2");
    assert_eq!(
        (p.grid.pad(0, 0), p.grid.pad(7, 0), p.grid.pad(0, 7)),
        (Some(Control::Note(1, 0x00)), Some(Control::Note(1, 0x07)), Some(Control::Note(1, 0x38)))
    );
    assert_eq!(p.grid.pad(7, 7), Some(Control::Note(1, 0x3F)));
    assert_eq!(fader(&p, FaderTarget::Layer(1)), Control::Cc(1, 0x30));
    assert_eq!(fader(&p, FaderTarget::Master), Control::Cc(1, 0x38));
    assert_eq!(button(&p, Action::Column(1)), Control::Note(1, 0x64));
    assert_eq!(button(&p, Action::Stop(8)), Control::Note(1, 0x70));
    assert_eq!(p.shift, Some(Control::Note(1, 0x7A)));
    assert!(p.hello.is_empty());
    // Channel 7 (status 0x96) is full brightness; 21 the palette's green.
    assert_eq!(Control::Note(1, 0x00).light_message(p.colours.playing), [0x96, 0x00, 21]);
    // Akai, "APC40 mkII Communication Protocol" v1.2: Type 0 introduction, Ableton Live mode.
    let p = bundled("apc40-mk2");
    assert_eq!(&p.hello[..8], &[0xF0, 0x47, 0x7F, 0x29, 0x60, 0x00, 0x04, 0x41]);
    assert_eq!((p.hello.len(), p.hello[11]), (12, 0xF7));
    assert_eq!(
        (p.grid.pad(0, 0), p.grid.pad(0, 4), p.grid.pad(7, 4)),
        (Some(Control::Note(1, 0x00)), Some(Control::Note(1, 0x20)), Some(Control::Note(1, 0x27)))
    );
    assert_eq!(fader(&p, FaderTarget::Layer(3)), Control::Cc(3, 0x07));
    assert_eq!(fader(&p, FaderTarget::Master), Control::Cc(1, 0x0E));
    assert_eq!(
        [Action::PageUp, Action::PageDown, Action::PageRight, Action::PageLeft].map(|a| button(&p, a)),
        [0x5E, 0x5F, 0x60, 0x61].map(|n| Control::Note(1, n))
    );
    assert_eq!(
        (button(&p, Action::Tap), button(&p, Action::Column(2))),
        (Control::Note(1, 0x63), Control::Note(2, 0x33))
    );
    // Novation, "Launchpad X / Launchpad Mini [MK3] Programmer's Reference Manual".
    for (name, device) in [("launchpad-x", 0x0C), ("launchpad-mini-mk3", 0x0D)] {
        let p = bundled(name);
        assert_eq!(p.hello, [0xF0, 0x00, 0x20, 0x29, 0x02, device, 0x0E, 0x01, 0xF7], "{name}");
        assert_eq!((p.grid.pad(0, 0), p.grid.pad(7, 7)), (Some(Control::Note(1, 11)), Some(Control::Note(1, 88))));
        assert_eq!(p.grid.pad(2, 4), Some(Control::Note(1, 53)));
        assert_eq!(
            [Action::PageUp, Action::PageDown, Action::PageLeft, Action::PageRight].map(|a| button(&p, a)),
            [91, 92, 93, 94].map(|n| Control::Cc(1, n))
        );
        assert_eq!(
            (button(&p, Action::Stop(8)), button(&p, Action::Stop(1))),
            (Control::Cc(1, 89), Control::Cc(1, 19))
        );
        // A static light on channel 1; a control change lights with a control change.
        assert_eq!(Control::Cc(1, 91).light_message(Light { channel: 1, value: 3 }), [0xB0, 91, 3]);
    }
}

#[test]
fn a_bad_profile_is_one_located_sentence() {
    let good = BUNDLED.iter().find(|(f, _)| *f == "generic-grid.ron").unwrap().1;
    let twice = good.replace("Note(10, 61), action: Back", "Note(10, 60), action: Back");
    let e = Profile::parse(&twice, "mine.ron").unwrap_err();
    assert!(e.starts_with("mine.ron: Note(10, 60) (Back) is used twice"), "{e}");
    let on_grid = good.replace("Note(10, 60), action: Go", "Note(10, 40), action: Go");
    assert!(Profile::parse(&on_grid, "mine.ron").unwrap_err().contains("used twice"));
    let e = Profile::parse(&good.replace("ports: [\"indra grid\"],", "ports: [\"x\"], hello: [0x90, 1],"), "m.ron");
    assert!(e.unwrap_err().contains("`hello` must be one SysEx message"));
    let e = Profile::parse(&good.replace("columns: 4", "columns: 4, colour: 3"), "m.ron").unwrap_err();
    assert!(e.starts_with("m.ron:") && e.contains("colour"), "{e}");
    let e = Profile::parse(&good.replace("Note(10, 36)", "Note(17, 36)"), "m.ron").unwrap_err();
    assert!(e.contains("channels are 1–16"), "{e}");
}

/// A show of two layers: kleinian, star_glow and a missing scene on the first (nothing
/// starts: the show has cues), poisson_2d waiting for the bar on the second.
fn show() -> Scene {
    let assets = crate::assets::Assets::new(Some(env!("CARGO_MANIFEST_DIR").into()));
    let text = r#"(
        name: "pads", size: (64, 64), bpm: 120.0,
        columns: ["a", "b", "c"],
        layers: [
            (name: "one", clips: [(scene: "kleinian"), (scene: "star_glow"), (scene: "no_such_scene")]),
            (name: "two", clips: [(scene: "poisson_2d", transition: (kind: "crossfade", beats: 1.0, quantize: Bar))]),
        ],
        cues: [(name: "start", clips: [(1, 1)])],
    )"#;
    crate::scene::show::parse_show(&assets, "pads.ron", text, true).unwrap()
}

fn view<'a>(scene: &'a Scene, params: &'a [ParamSet], state: &'a ShowState, beats: f64) -> SceneView<'a> {
    let show = scene.show.as_deref().unwrap();
    SceneView { scene, params, tempo: TempoClock { bpm: 120.0, beats }, show: Some((show, state)) }
}

fn note(note: u8) -> MidiEvent {
    MidiEvent::NoteOn { channel: 1, note, velocity: 127 }
}

#[test]
fn pads_trigger_their_clips_and_light_with_the_show_state() {
    let scene = show();
    let show = scene.show.as_deref().unwrap();
    let params: Vec<ParamSet> = scene.nodes.iter().map(|n| n.params.clone()).collect();
    let mut state = ShowState::new(show);
    state.step(show, Clock { frame: 0, seconds: 0.0, beats: 0.0 });
    let mut surface = Surface::new(bundled("launchpad-x"));
    let v = view(&scene, &params, &state, 0.1);
    // The cue started clip 1 of layer 1 (the bottom row); the missing scene is broken.
    let states: Vec<PadState> = (0..4).map(|c| surface.pad_state(&v, c, 0)).collect();
    assert_eq!(states, [PadState::Playing, PadState::Loaded, PadState::Broken, PadState::Empty]);
    assert_eq!(surface.pad_state(&v, 0, 1), PadState::Loaded);
    let handled = surface.handle(note(12), &v);
    assert_eq!(handled.events, [ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(1) })]);
    assert!(handled.used && surface.handle(note(14), &v).events.is_empty(), "an empty pad does nothing");
    // A quantized trigger blinks in the first half of each beat until its bar.
    let trigger = surface.handle(note(21), &v).events;
    let [ControlEvent::Show(command)] = trigger[..] else { panic!("{trigger:?}") };
    state.request(show, command).unwrap();
    for (frame, beats, want) in
        [(1, 0.2, PadState::Queued), (2, 0.6, PadState::Loaded), (3, 1.3, PadState::Queued), (4, 3.9, PadState::Loaded)]
    {
        state.step(show, Clock { frame, seconds: beats / 2.0, beats });
        assert_eq!(surface.pad_state(&view(&scene, &params, &state, beats), 0, 1), want, "at beat {beats}");
    }
    state.step(show, Clock { frame: 240, seconds: 2.0, beats: 4.0 });
    assert_eq!(surface.pad_state(&view(&scene, &params, &state, 4.1), 0, 1), PadState::Playing);
    let lights = surface.lights(&view(&scene, &params, &state, 4.1));
    assert!(lights.contains(&(Control::Note(1, 21), surface.profile.colours.playing)));
    assert!(lights.contains(&(Control::Cc(1, 96), Light { channel: 1, value: 45 })), "GO is lit: the show has cues");
    assert!(lights.contains(&(Control::Cc(1, 94), Light { channel: 1, value: 0 })), "one page: no paging right");
}

#[test]
fn paging_moves_the_grid_and_faders_pick_up_before_they_move_a_layer() {
    let scene = show();
    let show = scene.show.as_deref().unwrap();
    let mut params: Vec<ParamSet> = scene.nodes.iter().map(|n| n.params.clone()).collect();
    let state = ShowState::new(show);
    // A 4×4 grid over three clips across: one page; two layers: one page.
    let mut surface = Surface::new(bundled("generic-grid"));
    let press = |s: &mut Surface, n: u8, v: &SceneView<'_>| {
        s.handle(MidiEvent::NoteOn { channel: 10, note: n, velocity: 100 }, v)
    };
    press(&mut surface, 66, &view(&scene, &params, &state, 0.0));
    assert_eq!(surface.page, (0, 0), "no page to the right of the only one");
    let mut narrow = bundled("generic-grid");
    narrow.grid.columns = 2;
    narrow.grid.rows = 1;
    let mut surface = Surface::new(narrow);
    press(&mut surface, 66, &view(&scene, &params, &state, 0.0));
    press(&mut surface, 63, &view(&scene, &params, &state, 0.0));
    assert_eq!(surface.page, (1, 1));
    let events = press(&mut surface, 36, &view(&scene, &params, &state, 0.0)).events;
    assert!(events.is_empty(), "page (1,1) pad 1 is layer 2's third clip: none");
    press(&mut surface, 64, &view(&scene, &params, &state, 0.0));
    let events = press(&mut surface, 36, &view(&scene, &params, &state, 0.0)).events;
    assert_eq!(events, [ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(2) })]);
    // Layer 1's opacity is 1.0: a fader at 0 waits until it reaches it (pickup).
    let node = show.layers[0].node;
    let opacity = params[node].index("opacity").unwrap();
    let cc = |s: &mut Surface, value: u8, p: &[ParamSet]| {
        s.handle(MidiEvent::Cc { channel: 10, controller: 20, value }, &view(&scene, p, &state, 0.0)).events
    };
    assert!(cc(&mut surface, 0, &params).is_empty() && cc(&mut surface, 90, &params).is_empty());
    let events = cc(&mut surface, 127, &params);
    let [ControlEvent::Write(w)] = events[..] else { panic!("{events:?}") };
    assert_eq!((w.node, w.param, w.value), (node, opacity, ParamValue::Float(1.0)));
    // Picked up: it follows from here, down as well.
    params[node].set_at(opacity, ParamValue::Float(1.0));
    let events = cc(&mut surface, 64, &params);
    let [ControlEvent::Write(w)] = events[..] else { panic!("{events:?}") };
    assert!(matches!(w.value, ParamValue::Float(v) if (v - 64.0 / 127.0).abs() < 1e-6));
    // Someone else moved it (OSC): the fader must pick it up again.
    params[node].set_at(opacity, ParamValue::Float(0.1));
    assert!(cc(&mut surface, 100, &params).is_empty());
}
