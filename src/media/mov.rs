//! The sample tables of a QuickTime (`.mov`) or MP4 file's first video track: where each frame's
//! bytes are and when it is shown, so frame n is one seek and one read — no decoder state. Only
//! what an intra-only codec (HAP) needs is read: the track's codec and size, its time scale, and
//! the `stts`, `stsc`, `stsz` and `stco`/`co64` tables. Edit lists are not applied (a HAP clip
//! plays its samples from the first).
//!
//! Written here rather than taken from an MP4 crate: those read MP4's codecs and refuse or skip
//! QuickTime sample descriptions they do not know (such as `Hap1`), and the part needed is small.
//! Every size in the file is checked against the file and against [`MOOV_LIMIT`] before anything
//! is allocated from it, so a truncated or hostile file is an error, never a huge allocation.

use std::io::{Read, Seek, SeekFrom};

/// The largest `moov` atom read (a ten-hour 60 fps clip's tables take about 10 MB).
pub const MOOV_LIMIT: u64 = 64 << 20;

/// Where one frame is in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// Byte offset from the start of the file.
    pub offset: u64,
    /// Bytes.
    pub size: u32,
}

/// A video track's frames.
#[derive(Clone, Debug)]
pub struct VideoTrack {
    /// The sample description's four-character code (`Hap1`, `Hap5`, `HapY`, `avc1`, …).
    pub codec: [u8; 4],
    /// Frame size in pixels, from the sample description.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Units per second of the sample times.
    pub timescale: u32,
    /// Each frame's place in the file.
    pub samples: Vec<Sample>,
    /// Each frame's start time, in `timescale` units (ascending), and the track's end after the
    /// last.
    pub starts: Vec<u64>,
}

impl VideoTrack {
    /// The codec as text.
    pub fn codec_name(&self) -> String {
        String::from_utf8_lossy(&self.codec).into_owned()
    }

    /// The clip's length in seconds.
    pub fn duration(&self) -> f64 {
        self.starts.last().copied().unwrap_or(0) as f64 / f64::from(self.timescale.max(1))
    }

    /// Frames per second, averaged over the clip.
    pub fn fps(&self) -> f64 {
        let duration = self.duration();
        if duration > 0.0 { self.samples.len() as f64 / duration } else { 0.0 }
    }

    /// The frame shown at `seconds` into the clip (clamped to the first and last frames).
    pub fn frame_at(&self, seconds: f64) -> usize {
        let count = self.samples.len();
        if count == 0 {
            return 0;
        }
        // Half a time unit absorbs float error at frame boundaries (n / fps is frame n).
        let t = (seconds * f64::from(self.timescale) + 0.5).max(0.0) as u64;
        let after = self.starts[..count].partition_point(|&start| start <= t);
        after.saturating_sub(1).min(count - 1)
    }
}

/// Reads the first video track of the QuickTime or MP4 file `file` (`len` bytes long).
pub fn read_video_track(file: &mut (impl Read + Seek), len: u64) -> Result<VideoTrack, String> {
    let moov = find_moov(file, len)?;
    let mut tracks = Atoms::new(&moov).filter(|a| a.kind == *b"trak");
    let track = tracks
        .find_map(|trak| parse_track(trak.body, len).transpose())
        .transpose()?
        .ok_or("the file has no video track")?;
    for sample in &track.samples {
        if sample.offset.checked_add(u64::from(sample.size)).is_none_or(|end| end > len) {
            return Err(format!(
                "the file is truncated: a frame at byte {} of {} bytes ends past its end ({len} bytes)",
                sample.offset, sample.size
            ));
        }
    }
    Ok(track)
}

/// The body of the top-level `moov` atom, wherever it is (before or after `mdat`).
fn find_moov(file: &mut (impl Read + Seek), len: u64) -> Result<Vec<u8>, String> {
    let io = |e: std::io::Error| format!("not a QuickTime/MP4 file, or truncated ({e})");
    let mut at = 0u64;
    while at + 8 <= len {
        file.seek(SeekFrom::Start(at)).map_err(io)?;
        let mut head = [0u8; 16];
        file.read_exact(&mut head[..8]).map_err(io)?;
        let size32 = u32::from_be_bytes(head[..4].try_into().unwrap());
        let kind: [u8; 4] = head[4..8].try_into().unwrap();
        let (size, header) = match size32 {
            0 => (len - at, 8),
            1 => {
                file.read_exact(&mut head[8..16]).map_err(io)?;
                (u64::from_be_bytes(head[8..16].try_into().unwrap()), 16)
            }
            n => (u64::from(n), 8),
        };
        // Checked: a 64-bit size that wraps the offset walked back and forth for ever.
        if size < header || at.checked_add(size).is_none_or(|end| end > len) {
            return Err(format!(
                "not a QuickTime/MP4 file, or truncated: the '{}' atom at byte {at} claims {size} bytes of {len}",
                String::from_utf8_lossy(&kind)
            ));
        }
        if kind == *b"moov" {
            let body = size - header;
            if body > MOOV_LIMIT {
                return Err(format!("its index (moov) is {body} bytes, more than the {MOOV_LIMIT} read"));
            }
            let mut moov = vec![0u8; body as usize];
            file.read_exact(&mut moov).map_err(io)?;
            return Ok(moov);
        }
        at += size;
    }
    Err("not a QuickTime/MP4 file, or truncated: it has no index (moov atom)".into())
}

/// One atom inside a parsed parent.
struct Atom<'a> {
    kind: [u8; 4],
    body: &'a [u8],
}

/// The atoms in `bytes`, in order; iteration stops at the first one that does not fit.
struct Atoms<'a> {
    bytes: &'a [u8],
}

impl<'a> Atoms<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Self { bytes }
    }
}

impl<'a> Iterator for Atoms<'a> {
    type Item = Atom<'a>;

    fn next(&mut self) -> Option<Atom<'a>> {
        let size32 = be32(self.bytes, 0)?;
        let kind: [u8; 4] = self.bytes.get(4..8)?.try_into().ok()?;
        let (size, header) = match size32 {
            0 => (self.bytes.len(), 8),
            1 => (usize::try_from(be64(self.bytes, 8)?).ok()?, 16),
            n => (n as usize, 8),
        };
        if size < header || size > self.bytes.len() {
            self.bytes = &[];
            return None;
        }
        let body = &self.bytes[header..size];
        self.bytes = &self.bytes[size..];
        Some(Atom { kind, body })
    }
}

fn child<'a>(parent: &'a [u8], kind: &[u8; 4]) -> Option<&'a [u8]> {
    Atoms::new(parent).find(|a| a.kind == *kind).map(|a| a.body)
}

fn be16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn be32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn be64(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_be_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// The entries of a full atom's table (`version/flags`, then `count` entries of `width` bytes
/// after `skip` more bytes), checked to fit.
fn table<'a>(body: &'a [u8], skip: usize, width: usize, what: &str) -> Result<(usize, &'a [u8]), String> {
    let bad = || format!("its {what} table is damaged");
    let count = be32(body, 4 + skip).ok_or_else(bad)? as usize;
    let start = 8 + skip;
    let bytes = count.checked_mul(width).ok_or_else(bad)?;
    let entries = body.get(start..start + bytes).ok_or_else(bad)?;
    Ok((count, entries))
}

/// A `trak` atom's frames, or `None` when it is not a video track (in a file of `len` bytes).
fn parse_track(trak: &[u8], len: u64) -> Result<Option<VideoTrack>, String> {
    let missing = |what: &str| format!("its video track has no {what}");
    let Some(mdia) = child(trak, b"mdia") else { return Ok(None) };
    let handler = child(mdia, b"hdlr").and_then(|h| h.get(8..12));
    if handler != Some(b"vide") {
        return Ok(None);
    }
    let mdhd = child(mdia, b"mdhd").ok_or_else(|| missing("media header"))?;
    let timescale = match mdhd.first() {
        Some(1) => be32(mdhd, 20),
        _ => be32(mdhd, 12),
    }
    .filter(|&t| t > 0)
    .ok_or("its media header has no time scale")?;
    let stbl = child(mdia, b"minf").and_then(|m| child(m, b"stbl")).ok_or_else(|| missing("sample table"))?;

    let stsd = child(stbl, b"stsd").ok_or_else(|| missing("sample description"))?;
    let entry = stsd.get(8..).ok_or("its sample description is damaged")?;
    let codec: [u8; 4] = entry.get(4..8).and_then(|c| c.try_into().ok()).ok_or("its sample description is damaged")?;
    let width = u32::from(be16(entry, 32).ok_or("its sample description is damaged")?);
    let height = u32::from(be16(entry, 34).ok_or("its sample description is damaged")?);

    let sizes = sample_sizes(child(stbl, b"stsz").ok_or_else(|| missing("sample size table"))?, len)?;
    let chunks = chunk_offsets(stbl)?;
    let stsc = child(stbl, b"stsc").ok_or_else(|| missing("sample-to-chunk table"))?;
    let samples = place_samples(&sizes, &chunks, stsc)?;
    let starts = sample_starts(child(stbl, b"stts").ok_or_else(|| missing("time-to-sample table"))?, samples.len())?;
    Ok(Some(VideoTrack { codec, width, height, timescale, samples, starts }))
}

/// Each frame's size; frames of one uniform size must fit in the file's `len` bytes before a
/// table of them is made (a 343-byte file claiming 67 million frames took 1.8 GB).
fn sample_sizes(stsz: &[u8], len: u64) -> Result<Vec<u32>, String> {
    let uniform = be32(stsz, 4).ok_or("its sample size table is damaged")?;
    if uniform != 0 {
        let count = be32(stsz, 8).ok_or("its sample size table is damaged")?;
        if u64::from(count) * u64::from(uniform) > len {
            return Err(format!("its sample size table claims {count} frames of {uniform} bytes in a file of {len}"));
        }
        return Ok(vec![uniform; count as usize]);
    }
    let (_, entries) = table(stsz, 4, 4, "sample size")?;
    Ok(entries.chunks_exact(4).map(|e| u32::from_be_bytes(e.try_into().unwrap())).collect())
}

fn chunk_offsets(stbl: &[u8]) -> Result<Vec<u64>, String> {
    if let Some(stco) = child(stbl, b"stco") {
        let (_, entries) = table(stco, 0, 4, "chunk offset")?;
        return Ok(entries.chunks_exact(4).map(|e| u64::from(u32::from_be_bytes(e.try_into().unwrap()))).collect());
    }
    let co64 = child(stbl, b"co64").ok_or("its video track has no chunk offset table")?;
    let (_, entries) = table(co64, 0, 8, "chunk offset")?;
    Ok(entries.chunks_exact(8).map(|e| u64::from_be_bytes(e.try_into().unwrap())).collect())
}

/// Each sample's offset: chunks hold runs of samples back to back (`stsc` says how many).
fn place_samples(sizes: &[u32], chunks: &[u64], stsc: &[u8]) -> Result<Vec<Sample>, String> {
    let (_, entries) = table(stsc, 0, 12, "sample-to-chunk")?;
    let runs: Vec<(usize, usize)> =
        entries.chunks_exact(12).map(|e| (be32(e, 0).unwrap() as usize, be32(e, 4).unwrap() as usize)).collect();
    let mut samples = Vec::with_capacity(sizes.len());
    for (i, &(first, per_chunk)) in runs.iter().enumerate() {
        let end = runs.get(i + 1).map_or(chunks.len() + 1, |next| next.0);
        if first == 0 || end < first {
            return Err("its sample-to-chunk table is damaged".into());
        }
        for chunk in first..end.min(chunks.len() + 1) {
            let mut offset = chunks[chunk - 1];
            for _ in 0..per_chunk {
                let Some(&size) = sizes.get(samples.len()) else { return Ok(samples) };
                samples.push(Sample { offset, size });
                offset = offset.checked_add(u64::from(size)).ok_or("its chunk offset table is damaged")?;
            }
        }
    }
    if samples.len() < sizes.len() {
        return Err(format!("its tables place {} of its {} frames", samples.len(), sizes.len()));
    }
    Ok(samples)
}

/// Start times from the run-length `stts` table, plus the end time.
fn sample_starts(stts: &[u8], count: usize) -> Result<Vec<u64>, String> {
    let (_, entries) = table(stts, 0, 8, "time-to-sample")?;
    let mut starts = Vec::with_capacity(count + 1);
    let mut t = 0u64;
    for e in entries.chunks_exact(8) {
        let (run, delta) = (be32(e, 0).unwrap(), be32(e, 4).unwrap());
        for _ in 0..run {
            if starts.len() == count {
                break;
            }
            starts.push(t);
            t += u64::from(delta);
        }
    }
    if starts.len() < count {
        return Err(format!("its time table times {} of its {count} frames", starts.len()));
    }
    starts.push(t);
    Ok(starts)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn atom(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
        let mut out = ((body.len() + 8) as u32).to_be_bytes().to_vec();
        out.extend(kind);
        out.extend(body);
        out
    }

    #[test]
    fn a_file_that_is_not_a_movie_is_an_error_not_a_panic() {
        for bytes in [&b""[..], b"hello, world: not a movie at all", &[0xff; 64], &[0, 0, 0, 1, b'm', b'o', b'o', b'v']]
        {
            let e = read_video_track(&mut std::io::Cursor::new(bytes), bytes.len() as u64).unwrap_err();
            assert!(e.contains("QuickTime") || e.contains("moov"), "{e}");
        }
        // A moov with a track whose tables are garbage.
        let trak = atom(b"trak", &atom(b"mdia", &atom(b"hdlr", b"\0\0\0\0mhlrvide")));
        let file = atom(b"moov", &trak);
        let e = read_video_track(&mut std::io::Cursor::new(&file), file.len() as u64).unwrap_err();
        assert!(e.contains("media header"), "{e}");
    }

    #[test]
    fn an_atom_size_that_wraps_the_offset_is_an_error_not_an_endless_walk() {
        // 48 bytes: a `free` atom whose 64-bit size brings the offset back to 8 when added.
        let mut file = [0u8, 0, 0, 8].to_vec();
        file.extend(b"skip");
        file.extend([0, 0, 0, 1]);
        file.extend(b"free");
        file.extend((u64::MAX - 7).to_be_bytes());
        file.resize(48, 0);
        let e = read_video_track(&mut std::io::Cursor::new(&file), 48).unwrap_err();
        assert!(e.contains("'free' atom at byte 8 claims"), "{e}");
    }

    #[test]
    fn a_frame_count_larger_than_the_file_is_refused_before_any_table_is_made() {
        // A video track whose uniform-size `stsz` claims 67 million frames of 16 bytes.
        let full = |kind: &[u8; 4], body: &[u8]| atom(kind, &[&[0u8; 4][..], body].concat());
        let mut stsd_entry = vec![0u8; 36];
        stsd_entry[4..8].copy_from_slice(b"Hap1");
        let stbl = [
            full(b"stsd", &[&1u32.to_be_bytes()[..], &stsd_entry].concat()),
            full(b"stsz", &[16u32.to_be_bytes(), (1u32 << 26).to_be_bytes()].concat()),
            full(b"stco", &1u32.to_be_bytes()),
            full(b"stsc", &0u32.to_be_bytes()),
            full(b"stts", &0u32.to_be_bytes()),
        ]
        .concat();
        let mdhd = full(b"mdhd", &[[0u8; 8].as_slice(), &600u32.to_be_bytes()].concat());
        let hdlr = atom(b"hdlr", b"\0\0\0\0mhlrvide");
        let mdia = atom(b"mdia", &[mdhd, hdlr, atom(b"minf", &atom(b"stbl", &stbl))].concat());
        let file = atom(b"moov", &atom(b"trak", &mdia));
        assert!(file.len() < 400, "{} bytes", file.len());
        let e = read_video_track(&mut std::io::Cursor::new(&file), file.len() as u64).unwrap_err();
        assert!(e.contains("claims 67108864 frames of 16 bytes"), "{e}");
    }
}
