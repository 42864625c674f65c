//! An ISF node's checkpoint: its persistent targets (both halves of each and which is
//! current), the only state an ISF shader keeps from one frame to the next.

use super::{Feedback, IsfNode};
use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::Gpu;
use crate::techniques::isf::targets::{BYTE_FORMAT, FLOAT_FORMAT};
use crate::techniques::saved::{load_texture, save_texture};

/// One persistent target as the checkpoint lists it: name, width, height, float, current side.
type Listed = (String, u32, u32, bool, usize);

/// Saves every persistent target.
pub fn save(node: &IsfNode, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
    let mut listed: Vec<Listed> = Vec::new();
    for (name, Feedback { buffers, size, format }) in &node.feedback {
        let (sides, current) = buffers.sides();
        listed.push((name.clone(), size.0, size.1, *format == FLOAT_FORMAT, current));
        for (i, side) in sides.iter().enumerate() {
            save_texture(gpu, state, &format!("target/{name}/{i}"), &side.texture)?;
        }
    }
    state.put("targets", ron::to_string(&listed).expect("a list serialises").into_bytes());
    Ok(())
}

/// Makes the persistent targets a checkpoint lists and puts their pictures back.
pub fn load(node: &mut IsfNode, gpu: &Gpu, state: &NodeState) -> Result<(), CheckpointError> {
    let text = std::str::from_utf8(state.get("targets")?).map_err(|_| state.error("targets", "is not text".into()))?;
    let listed: Vec<Listed> =
        ron::from_str(text).map_err(|e| state.error("targets", format!("does not parse: {e}")))?;
    let largest = gpu.device.limits().max_texture_dimension_2d;
    for (name, width, height, float, current) in listed {
        if width == 0 || height == 0 || width > largest || height > largest || current > 1 {
            return Err(state.error("targets", format!("'{name}' at {width}x{height} is not a target this node makes")));
        }
        let format = if float { FLOAT_FORMAT } else { BYTE_FORMAT };
        let target = node.feedback(&name, (width, height), format);
        target.buffers.set_current(current);
        let (sides, _) = target.buffers.sides();
        for (i, side) in sides.iter().enumerate() {
            load_texture(gpu, state, &format!("target/{name}/{i}"), &side.texture)?;
        }
    }
    Ok(())
}
