//! Audio analysis → parameter writes: each mapping follows one source (a band, the level, an
//! onset, a beat) with its own attack and release, scaled into a range — an envelope follower per
//! mapping, stepped with the frames it is fed, so a file's writes are the same every render.

use super::analysis::{AudioFrame, BANDS};
use crate::params::{ControlEvent, ParamType, ParamValue, ParamWrite, Source, Target};
use crate::scene::Scene;

pub use crate::scene::{AudioMapping, AudioSource};

/// Envelope followers of a scene's audio mappings.
#[derive(Clone, Debug)]
pub struct AudioMapper {
    mappings: Vec<AudioMapping>,
    envelopes: Vec<f32>,
    /// Mappings from here on were learned (the scene's come first).
    learned_from: usize,
    /// Whether a node samples the sound itself (each frame's [`ControlEvent::Audio`]).
    heard: bool,
}

impl AudioMapper {
    /// The followers of `scene`'s `controls.audio`, at rest.
    pub fn new(scene: &Scene) -> Self {
        Self::with_learned(scene, Vec::new())
    }

    /// The followers of `scene`'s mappings and then `learned` ones (applied after the scene's,
    /// so a learned mapping wins where both write one parameter), at rest.
    pub fn with_learned(scene: &Scene, learned: Vec<AudioMapping>) -> Self {
        let mappings: Vec<AudioMapping> = scene.audio.iter().cloned().chain(learned).collect();
        Self {
            envelopes: vec![0.0; mappings.len()],
            mappings,
            learned_from: scene.audio.len(),
            heard: scene.hears_audio(),
        }
    }

    /// Whether some mapping writes `node`'s parameter `param`, and whether a learned one does.
    pub fn maps(&self, node: usize, param: usize) -> (bool, bool) {
        let writes = |m: &AudioMapping| m.target.node == node && m.target.param == param;
        (self.mappings.iter().any(writes), self.mappings[self.learned_from..].iter().any(writes))
    }

    /// Whether the scene uses no audio: no mapping, and no node that samples it.
    pub fn is_empty(&self) -> bool {
        self.mappings.is_empty() && !self.heard
    }

    /// The writes for one frame of `dt` seconds: each mapping's envelope moves towards its
    /// source (attack when rising, release when falling) and is written across its range; an
    /// onset or beat mapped to a trigger fires it, a level fires it as it rises through half.
    pub fn events(&mut self, frame: &AudioFrame, dt: f64, scene: &Scene) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        if self.heard {
            events.push(ControlEvent::Audio(frame.snapshot.clone()));
        }
        for (m, envelope) in self.mappings.iter().zip(&mut self.envelopes) {
            let input = match m.source {
                AudioSource::Level => frame.level,
                AudioSource::Peak => frame.peak,
                AudioSource::Low => frame.low,
                AudioSource::Mid => frame.mid,
                AudioSource::High => frame.high,
                AudioSource::Band(b) => frame.bands.get(usize::from(b).min(BANDS - 1)).copied().unwrap_or(0.0),
                AudioSource::Onset => f32::from(u8::from(frame.onset)),
                AudioSource::Beat => f32::from(u8::from(frame.beat)),
            };
            let decl = &scene.nodes[m.target.node].params.decls()[m.target.param];
            if decl.ty() == ParamType::Trigger {
                // A pulse source fires on each pulse; a level fires as it rises through half.
                let pulse = matches!(m.source, AudioSource::Onset | AudioSource::Beat);
                if input > 0.5 && (pulse || *envelope <= 0.5) {
                    events.push(write(m.target, ParamValue::Trigger(true)));
                }
                *envelope = input;
                continue;
            }
            let seconds = if input > *envelope { m.attack } else { m.release };
            let k = if seconds <= 0.0 { 1.0 } else { 1.0 - (-dt / f64::from(seconds)).exp() as f32 };
            *envelope += (input - *envelope) * k;
            let (lo, hi) = m.range;
            let value = lo + (hi - lo) * envelope.clamp(0.0, 1.0);
            let value = match (m.target.component, decl.ty()) {
                (None, ParamType::Int) => ParamValue::Int(value.round() as i32),
                (None, ParamType::Bool) => ParamValue::Bool(value >= 0.5),
                _ => ParamValue::Float(value),
            };
            events.push(write(m.target, value));
        }
        events
    }
}

fn write(target: Target, value: ParamValue) -> ControlEvent {
    ControlEvent::Write(ParamWrite {
        node: target.node,
        param: target.param,
        component: target.component,
        value,
        source: Source::Audio,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::parse_scene;

    const SCENE: &str = r#"(
        name: "t", size: (8, 8), dt: 0.1,
        nodes: [(id: "fluid", technique: "grid_fluid")],
        output: "fluid",
        controls: (audio: [
            (source: Beat, target: "fluid.reset"),
            (source: Low, target: "fluid.reset"),
            (source: Low, target: "fluid.velocity_coef", range: (2.0, 6.0), attack: 0.0, release: 1.0),
        ]),
    )"#;

    /// How many times `events` fire the reset trigger.
    fn fired(events: &[ControlEvent], scene: &Scene) -> usize {
        let reset = scene.nodes[0].params.decls().iter().position(|d| d.name == "reset").unwrap();
        events.iter().filter(|e| matches!(e, ControlEvent::Write(w) if w.param == reset)).count()
    }

    #[test]
    fn a_beat_fires_its_trigger_a_level_fires_as_it_rises_and_an_envelope_releases() {
        let scene = parse_scene("t.ron", SCENE).unwrap();
        let mut mapper = AudioMapper::new(&scene);
        let frame = |low: f32, onset: bool, beat: bool| AudioFrame { low, onset, beat, ..AudioFrame::default() };
        // An onset off the beat fires neither trigger (the level one only listens to the level).
        assert_eq!(fired(&mapper.events(&frame(0.0, true, false), 0.1, &scene), &scene), 0);
        assert_eq!(fired(&mapper.events(&frame(0.0, true, true), 0.1, &scene), &scene), 1, "the beat");
        assert_eq!(fired(&mapper.events(&frame(0.8, false, false), 0.1, &scene), &scene), 1, "the rise");
        assert_eq!(fired(&mapper.events(&frame(0.9, false, false), 0.1, &scene), &scene), 0, "still high");
        // The level's envelope: attack 0 jumps, release 1 s decays by e^(-dt) per step.
        let events = mapper.events(&frame(0.0, false, false), 0.1, &scene);
        let Some(ControlEvent::Write(ParamWrite { value: ParamValue::Float(v), .. })) = events.last() else {
            panic!("{events:?}")
        };
        let expected = 2.0 + 4.0 * 0.9 * (-0.1f32).exp();
        assert!((v - expected).abs() < 1e-4, "{v} vs {expected}");
    }
}
