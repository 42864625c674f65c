//! Audio analysis → parameter writes: each mapping follows one source (a band, the level, an
//! onset) with its own attack and release, scaled into a range — an envelope follower per
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
}

impl AudioMapper {
    /// The followers of `scene`'s `controls.audio`, at rest.
    pub fn new(scene: &Scene) -> Self {
        Self { mappings: scene.audio.clone(), envelopes: vec![0.0; scene.audio.len()] }
    }

    /// Whether the scene maps any audio.
    pub fn is_empty(&self) -> bool {
        self.mappings.is_empty()
    }

    /// The writes for one frame of `dt` seconds: each mapping's envelope moves towards its
    /// source (attack when rising, release when falling) and is written across its range; an
    /// onset mapped to a trigger fires it.
    pub fn events(&mut self, frame: &AudioFrame, dt: f64, scene: &Scene) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        for (m, envelope) in self.mappings.iter().zip(&mut self.envelopes) {
            let input = match m.source {
                AudioSource::Level => frame.level,
                AudioSource::Peak => frame.peak,
                AudioSource::Low => frame.low,
                AudioSource::Mid => frame.mid,
                AudioSource::High => frame.high,
                AudioSource::Band(b) => frame.bands.get(usize::from(b).min(BANDS - 1)).copied().unwrap_or(0.0),
                AudioSource::Onset => f32::from(u8::from(frame.onset)),
            };
            let decl = &scene.nodes[m.target.node].params.decls()[m.target.param];
            if decl.ty() == ParamType::Trigger {
                if frame.onset || (m.source != AudioSource::Onset && input > 0.5 && *envelope <= 0.5) {
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
