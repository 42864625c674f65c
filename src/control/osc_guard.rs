//! Checks a raw OSC packet before it is decoded: how deeply bundles nest in bundles and arrays in
//! type tags. rosc decodes (and Rust drops and formats) nested values recursively, so one crafted
//! packet of a few thousand levels would overflow a thread's stack and abort the show; real OSC
//! peers use a handful of levels. The walk here is iterative and allocates only its work list.

/// Deepest nesting accepted, for bundles in bundles and for `[` arrays in a type tag string.
pub const MAX_NESTING: usize = 16;

/// `Err` with a short reason if bundles or arrays nest deeper than [`MAX_NESTING`]. Anything
/// else that is malformed is left for the decoder to report.
pub fn check_nesting(packet: &[u8]) -> Result<(), String> {
    let mut work = vec![(packet, 1usize)];
    while let Some((bytes, depth)) = work.pop() {
        if bytes.starts_with(b"#bundle\0") {
            if depth > MAX_NESTING {
                return Err(format!("bundles nested deeper than {MAX_NESTING}"));
            }
            // "#bundle\0", an 8-byte time tag, then (size, element) pairs.
            let mut at = 16;
            while let Some(size) = bytes.get(at..at + 4) {
                let size = u32::from_be_bytes([size[0], size[1], size[2], size[3]]) as usize;
                at += 4;
                let Some(element) = bytes.get(at..at.saturating_add(size)) else { break };
                work.push((element, depth + 1));
                at += size;
            }
        } else if array_depth(bytes) > MAX_NESTING {
            return Err(format!("arguments nested deeper than {MAX_NESTING} arrays"));
        }
    }
    Ok(())
}

/// The deepest `[` nesting in a message's type tag string (0 when it has none or is malformed).
fn array_depth(message: &[u8]) -> usize {
    // The address is a NUL-terminated string padded to 4 bytes; the type tags follow.
    let Some(end) = message.iter().position(|&b| b == 0) else { return 0 };
    let tags_at = (end + 4) & !3;
    let Some(tags) = message.get(tags_at..) else { return 0 };
    let (mut depth, mut deepest) = (0usize, 0usize);
    for &tag in tags.iter().take_while(|&&b| b != 0) {
        match tag {
            b'[' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b']' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bundle holding `inner` (one element).
    fn bundle(inner: &[u8]) -> Vec<u8> {
        let mut b = b"#bundle\0".to_vec();
        b.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1]);
        b.extend_from_slice(&(inner.len() as u32).to_be_bytes());
        b.extend_from_slice(inner);
        b
    }

    fn message_with_tags(tags: &str) -> Vec<u8> {
        let mut m = b"/a\0\0".to_vec();
        m.extend_from_slice(tags.as_bytes());
        m.push(0);
        while !m.len().is_multiple_of(4) {
            m.push(0);
        }
        m
    }

    #[test]
    fn ordinary_packets_pass_and_deep_nesting_is_refused() {
        let msg = message_with_tags(",f[ii]");
        assert!(check_nesting(&msg).is_ok());
        let mut nested = msg.clone();
        for _ in 0..MAX_NESTING {
            nested = bundle(&nested);
        }
        assert!(check_nesting(&nested).is_ok(), "{MAX_NESTING} bundles in bundles are fine");
        assert!(check_nesting(&bundle(&nested)).unwrap_err().contains("bundles"));
        // The packet that used to overflow the OSC thread: thousands of levels.
        let mut deep = msg;
        for _ in 0..3000 {
            deep = bundle(&deep);
        }
        assert!(check_nesting(&deep).is_err());
        let arrays = message_with_tags(&format!(",{}{}", "[".repeat(15_000), "]".repeat(15_000)));
        assert!(check_nesting(&arrays).unwrap_err().contains("arrays"));
        assert!(check_nesting(&message_with_tags(&format!(",{}", "[".repeat(MAX_NESTING)))).is_ok());
    }

    #[test]
    fn garbage_is_left_to_the_decoder() {
        for bytes in [&b""[..], b"#bundle\0", b"#bundle\0\0\0\0\0\0\0\0\0\xff\xff\xff\xff", b"/no-nul"] {
            assert!(check_nesting(bytes).is_ok());
        }
    }
}
