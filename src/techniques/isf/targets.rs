//! The sizes of an ISF node's pass targets and the memory they take together. Each size is an
//! expression over `$WIDTH`, `$HEIGHT` and the inputs; the node's targets are bounded as a whole,
//! not pass by pass: four persistent 8192² float targets, each under any per-pass bound, took a
//! process to 4 GB and a crash. A persistent target counts twice (it is ping-ponged).

use super::expr;
use super::header::{Header, Pass};

/// A target without `FLOAT`: 8 bits a channel, as GL hosts make them.
pub const BYTE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// A `FLOAT` target (half floats: filterable everywhere, enough for feedback).
pub const FLOAT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The most texture memory one ISF node's targets may take together, persistent ones counted
/// twice: an eighth of a scene's whole budget.
pub const MAX_NODE_TARGET_BYTES: u64 = 1 << 30;

/// Every pass's size at render size `output`, each side evaluated by `var` (`WIDTH`, `HEIGHT`,
/// input names) and at most `max_side`; `Err` names the pass that cannot be made, or the total
/// when the targets together take more than [`MAX_NODE_TARGET_BYTES`].
pub fn pass_sizes(
    passes: &[Pass],
    output: (u32, u32),
    max_side: u32,
    var: &dyn Fn(&str) -> Option<f64>,
) -> Result<Vec<(u32, u32)>, String> {
    let side = |i: usize, expression: &Option<String>, full: u32, axis: &str| -> Result<u32, String> {
        let Some(text) = expression else { return Ok(full) };
        let v = expr::evaluate(text, var).map_err(|e| format!("{axis} of pass {i}: {e}"))?;
        // A fraction of a pixel (a small render of `$WIDTH / 100`) is one pixel, as in GL hosts.
        if !v.is_finite() || v <= 0.0 || v > f64::from(max_side) {
            return Err(format!(
                "{axis} of pass {i}, '{text}', is {v} at {}×{}; it must be above 0 and at most {max_side}",
                output.0, output.1
            ));
        }
        Ok(v.max(1.0) as u32)
    };
    let sizes = passes
        .iter()
        .enumerate()
        .map(|(i, pass)| Ok((side(i, &pass.width, output.0, "WIDTH")?, side(i, &pass.height, output.1, "HEIGHT")?)))
        .collect::<Result<Vec<_>, String>>()?;
    let total = target_bytes(passes, &sizes);
    if total > MAX_NODE_TARGET_BYTES {
        let mib = |b: u64| b >> 20;
        return Err(format!(
            "the passes' targets take {} MiB together at {}×{} (persistent ones twice); a node may take at most {} MiB",
            mib(total),
            output.0,
            output.1,
            mib(MAX_NODE_TARGET_BYTES)
        ));
    }
    Ok(sizes)
}

/// What `$name` means in `header`'s size expressions at render size `output`, with the inputs'
/// defaults (what `check` and the scene budget evaluate).
pub fn default_var(header: &Header, output: (u32, u32)) -> impl Fn(&str) -> Option<f64> + '_ {
    move |name: &str| match name {
        "WIDTH" => Some(f64::from(output.0)),
        "HEIGHT" => Some(f64::from(output.1)),
        _ => header.inputs.iter().find(|i| i.name == name).and_then(|i| i.number(i.decl()?.default)),
    }
}

/// The bytes the targets of ISF file `file` take at render size `output` with its defaults (0
/// where it cannot be read or sized: that is an error of its own, told by the scene loader).
pub fn declared_bytes(assets: &crate::assets::Assets, file: &str, output: (u32, u32)) -> u64 {
    let Ok(files) = super::IsfFiles::read(assets, file) else { return 0 };
    let Ok(header) = Header::parse(&files.fs.1) else { return 0 };
    let var = default_var(&header, output);
    pass_sizes(&header.passes, output, u32::MAX, &var).map_or(0, |sizes| target_bytes(&header.passes, &sizes))
}

/// The bytes the targets of `passes` at `sizes` take: each named target once (at the size of the
/// first pass that writes it), persistent ones twice, and every unnamed pass (the output).
pub fn target_bytes(passes: &[Pass], sizes: &[(u32, u32)]) -> u64 {
    let mut seen: Vec<&str> = Vec::new();
    let mut total = 0u64;
    for (pass, &size) in passes.iter().zip(sizes) {
        if let Some(target) = pass.target.as_deref() {
            if seen.contains(&target) {
                continue;
            }
            seen.push(target);
        }
        let format = if pass.float { FLOAT_FORMAT } else { BYTE_FORMAT };
        let copies = if pass.persistent { 2 } else { 1 };
        total = total.saturating_add(copies * crate::graph::texture_bytes(size, format));
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(target: &str, persistent: bool, float: bool, side: &str) -> Pass {
        Pass { target: Some(target.into()), persistent, float, width: Some(side.into()), height: Some(side.into()) }
    }

    #[test]
    fn the_targets_of_a_node_are_bounded_together() {
        let none = |_: &str| None;
        // One persistent float 8192² target: 8192² × 8 bytes × 2 = 1 GiB, just in.
        let one = [pass("a", true, true, "8192")];
        assert_eq!(target_bytes(&one, &[(8192, 8192)]), MAX_NODE_TARGET_BYTES);
        assert!(pass_sizes(&one, (64, 64), 16384, &none).is_ok());
        // Four of them (the hostile file): each fits, together they are refused.
        let four: Vec<Pass> = ["a", "b", "c", "d"].iter().map(|t| pass(t, true, true, "8192")).collect();
        let refused = pass_sizes(&four, (64, 64), 16384, &none).unwrap_err();
        assert!(refused.contains("4096 MiB together"), "{refused}");
        // A target written by two passes counts once; an 8-bit one a half of a float one.
        let twice = [pass("a", false, true, "4096"), pass("a", false, true, "4096"), pass("b", false, false, "4096")];
        assert_eq!(target_bytes(&twice, &[(4096, 4096); 3]), 4096 * 4096 * (8 + 4));
        let too_wide = pass_sizes(&[pass("a", false, false, "20000")], (64, 64), 16384, &none).unwrap_err();
        assert!(too_wide.contains("at most 16384"), "{too_wide}");
    }
}
