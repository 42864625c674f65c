use std::path::Path;

use super::*;

fn header() -> Header {
    Header {
        format: FORMAT,
        indra: "0.1.0".into(),
        scene: "cloth".into(),
        scene_hash: sha256_hex(b"scene"),
        controls_hash: sha256_hex(b""),
        adapter: "llvmpipe".into(),
        driver: "Mesa 25".into(),
        frame: 120,
        size: (96, 54),
        dt_bits: (1.0f32 / 60.0).to_bits(),
        seed: 7,
    }
}

fn sample() -> Checkpoint {
    let mut node = NodeState::new("node/0");
    node.put_pod("positions", &[[1.0f32, 2.0, 3.0, 4.0]; 3]);
    node.put_u64("frames", 42);
    let mut sections = vec![("control".to_string(), b"(params: [])".to_vec())];
    sections.extend(node.into_sections());
    Checkpoint { header: header(), sections }
}

#[test]
fn a_checkpoint_reads_back_as_written() {
    let bytes = sample().to_bytes();
    let back = Checkpoint::from_bytes(Path::new("c"), &bytes).unwrap();
    assert_eq!(back, sample());
    let node = NodeState::from_checkpoint("node/0", &back);
    assert_eq!(node.get_pod::<[f32; 4]>("positions").unwrap(), vec![[1.0, 2.0, 3.0, 4.0]; 3]);
    assert_eq!(node.get_u64("frames").unwrap(), 42);
    assert!(NodeState::from_checkpoint("node/1", &back).is_empty());
}

#[test]
fn a_checkpoint_is_written_atomically_and_its_header_read_alone() {
    let dir = std::env::temp_dir().join(format!("indra-ckpt-{}", std::process::id()));
    let path = dir.join("frame_120.ckpt");
    let written = sample().write(&path).unwrap();
    assert_eq!(std::fs::metadata(&path).unwrap().len(), written);
    assert_eq!(Checkpoint::read_header(&path).unwrap(), header());
    assert_eq!(Checkpoint::read(&path).unwrap(), sample());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn every_damaged_byte_and_every_cut_is_one_clear_error() {
    let bytes = sample().to_bytes();
    for i in (0..bytes.len()).step_by(7) {
        let mut bad = bytes.clone();
        bad[i] ^= 0x5a;
        let e = Checkpoint::from_bytes(Path::new("c.ckpt"), &bad).unwrap_err().to_string();
        assert!(e.starts_with("c.ckpt is not a usable checkpoint: "), "byte {i}: {e}");
    }
    for len in 0..bytes.len() {
        let e = Checkpoint::from_bytes(Path::new("c.ckpt"), &bytes[..len]).unwrap_err().to_string();
        assert!(e.contains("not a usable checkpoint"), "cut at {len}: {e}");
    }
}

#[test]
fn hostile_lengths_are_refused_before_anything_is_allocated() {
    // A well-formed checksum over a body that claims a section of 2⁶³ bytes.
    let mut body = Vec::new();
    body.extend_from_slice(MAGIC);
    let header = ron::to_string(&header()).unwrap();
    body.extend_from_slice(&(header.len() as u32).to_le_bytes());
    body.extend_from_slice(header.as_bytes());
    body.extend_from_slice(&1u32.to_le_bytes());
    body.extend_from_slice(&1u16.to_le_bytes());
    body.push(b'x');
    body.extend_from_slice(&(1u64 << 63).to_le_bytes());
    let digest = Sha256::digest(&body);
    body.extend_from_slice(&digest);
    let e = Checkpoint::from_bytes(Path::new("h"), &body).unwrap_err().to_string();
    assert!(e.contains("cut off"), "{e}");
}

#[test]
fn a_checkpoint_from_another_scene_size_or_adapter_is_refused_in_one_sentence() {
    let made = header();
    assert_eq!(made.mismatch(&header(), false), None);
    let changed = Header { scene_hash: sha256_hex(b"other"), ..header() };
    assert!(made.mismatch(&changed, true).unwrap().contains("another version of 'cloth'"));
    let sized = Header { size: (192, 108), ..header() };
    assert!(made.mismatch(&sized, false).unwrap().contains("96x54"));
    let gpu = Header { adapter: "NVIDIA H200".into(), ..header() };
    assert!(made.mismatch(&gpu, false).unwrap().contains("--accept-other-adapter"));
    assert_eq!(made.mismatch(&gpu, true), None);
}

#[test]
fn a_blob_of_the_wrong_size_names_its_section() {
    let mut node = NodeState::new("node/2/cloth");
    node.put("positions", vec![0; 12]);
    let e = node.get_exact("positions", 16).unwrap_err().to_string();
    assert_eq!(e, "checkpoint section 'node/2/cloth/positions': holds 12 bytes where this node has 16");
    assert!(node.get("velocity").unwrap_err().to_string().contains("missing"));
}
