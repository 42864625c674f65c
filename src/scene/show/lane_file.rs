//! Saving lanes edited live into the show file: the `lanes` list of its `timeline` written anew
//! and put in place of the old one, everything else in the file (comments, order, layout) as the
//! performer wrote it. The text is read with a small scanner that knows RON's strings, comments
//! and brackets; the result is parsed back and refused unless its lanes are the ones meant.

use super::file::ShowFile;
use crate::params::RawValue;
use crate::scene::schema::{TrackFile, ron_options};

/// Keys written on one line of a saved lane.
const KEYS_PER_LINE: usize = 6;

/// `text` (a show file) with its timeline's lanes replaced by `lanes`, or why it cannot be.
pub fn with_lanes(text: &str, lanes: &[TrackFile]) -> Result<String, String> {
    let b = text.as_bytes();
    let open = outer_open(b)?;
    let (fields, close) = fields(b, open)?;
    let spliced = match fields.iter().find(|f| f.name == "timeline") {
        Some(timeline) => {
            let open = struct_open(b, timeline.start).ok_or("the show's timeline is not a ( … ) section")?;
            let (inner, _) = self::fields(b, open)?;
            match inner.iter().find(|f| f.name == "lanes") {
                Some(old) => {
                    let list = lanes_text(lanes, indent_at(text, old.start) + 4);
                    format!("{}{list}{}", &text[..old.start], &text[old.end..])
                }
                None => {
                    let field = indent_at(text, timeline.start) + 4;
                    let list = lanes_text(lanes, field + 4);
                    format!("{}\n{}lanes: {list},{}", &text[..=open], " ".repeat(field), &text[open + 1..])
                }
            }
        }
        None => {
            // After the last field (and its comma), before any comment that ends its line.
            let (at, comma) = match fields.last() {
                Some(last) => match skip_trivia(b, last.end) {
                    after if b[after] == b',' => (after + 1, ""),
                    _ => (last.end, ","),
                },
                None => (close, ""),
            };
            let section = format!("{comma}\n    timeline: (\n        lanes: {},\n    ),", lanes_text(lanes, 8));
            format!("{}{section}{}", &text[..at], &text[at..])
        }
    };
    let parsed: ShowFile =
        ron_options().from_str(&spliced).map_err(|e| format!("the saved file would not parse: {e}"))?;
    if lanes_text(&parsed.timeline.lanes, 0) != lanes_text(lanes, 0) {
        return Err("the saved file would not read back with these lanes".into());
    }
    Ok(spliced)
}

/// `lanes` as RON, entries indented by `indent` spaces (the list's brackets by 4 fewer).
pub fn lanes_text(lanes: &[TrackFile], indent: usize) -> String {
    let pad = " ".repeat(indent);
    let mut out = String::from("[\n");
    for lane in lanes {
        let target = ron::to_string(&lane.target).unwrap_or_default();
        out.push_str(&format!("{pad}(target: {target}, interpolation: {:?}", lane.interpolation));
        if lane.repeat != crate::params::LoopMode::Once {
            out.push_str(&format!(", repeat: {:?}", lane.repeat));
        }
        if lane.time_scale != 1.0 {
            out.push_str(&format!(", time_scale: {}", number(f64::from(lane.time_scale))));
        }
        if lane.beats {
            out.push_str(", beats: true");
        }
        out.push_str(", keys: [");
        for (i, (time, value)) in lane.keys.iter().enumerate() {
            if lane.keys.len() > KEYS_PER_LINE && i % KEYS_PER_LINE == 0 {
                out.push_str(&format!("\n{pad}    "));
            } else if i > 0 {
                out.push(' ');
            }
            out.push_str(&format!("({}, {}),", number(f64::from(*time)), raw(value)));
        }
        if lane.keys.len() > KEYS_PER_LINE {
            out.push_str(&format!("\n{pad}"));
        }
        out.push_str("]),\n");
    }
    out.push_str(&" ".repeat(indent.saturating_sub(4)));
    out.push(']');
    out
}

/// The indentation of the line `at` is on.
fn indent_at(text: &str, at: usize) -> usize {
    let line = text[..at].rfind('\n').map_or(0, |i| i + 1);
    text[line..].chars().take_while(|c| *c == ' ').count()
}

/// A number as short as reads back the same: an f32's shortest form where it was one.
fn number(x: f64) -> String {
    let short = x as f32;
    if f64::from(short) == x { format!("{short:?}") } else { format!("{x:?}") }
}

fn raw(value: &RawValue) -> String {
    match value {
        RawValue::Bool(b) => b.to_string(),
        RawValue::Number(x) => number(*x),
        RawValue::List(v) => format!("({})", v.iter().map(|x| number(*x)).collect::<Vec<_>>().join(", ")),
        RawValue::Text(t) => ron::to_string(t).unwrap_or_default(),
    }
}

/// One field of a RON struct: its name and where its value starts and ends.
struct Field {
    name: String,
    start: usize,
    end: usize,
}

/// Where the file's outer `(` is: after attributes (`#![enable(…)]`) and an optional type name.
fn outer_open(b: &[u8]) -> Result<usize, String> {
    let mut i = skip_trivia(b, 0);
    while b[i..].starts_with(b"#!") {
        let open = skip_trivia(b, i + 2);
        if b.get(open) != Some(&b'[') {
            return Err("an attribute the scanner does not know".into());
        }
        let close = skip_trivia(b, value_end(b, open + 1)?);
        if b.get(close) != Some(&b']') {
            return Err("an attribute the scanner does not know".into());
        }
        i = skip_trivia(b, close + 1);
    }
    struct_open(b, i).ok_or_else(|| "the show file does not start with ( … )".into())
}

/// The `(` of a struct value at `i` (after an optional type name).
fn struct_open(b: &[u8], i: usize) -> Option<usize> {
    let mut i = skip_trivia(b, i);
    while b.get(i).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') {
        i += 1;
    }
    let i = skip_trivia(b, i);
    (b.get(i) == Some(&b'(')).then_some(i)
}

/// The fields of the struct whose `(` is at `open`, and where its `)` is.
fn fields(b: &[u8], open: usize) -> Result<(Vec<Field>, usize), String> {
    let mut out = Vec::new();
    let mut i = open + 1;
    loop {
        i = skip_trivia(b, i);
        match b.get(i) {
            None => return Err("the file ends inside a ( … )".into()),
            Some(b')') => return Ok((out, i)),
            Some(_) => {}
        }
        let name_start = i;
        while b.get(i).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') {
            i += 1;
        }
        let name = String::from_utf8_lossy(&b[name_start..i]).into_owned();
        i = skip_trivia(b, i);
        if name.is_empty() || b.get(i) != Some(&b':') {
            return Err(format!("expected a field name and ':' at byte {name_start}"));
        }
        let start = skip_trivia(b, i + 1);
        let end = value_end(b, start)?;
        out.push(Field { name, start, end });
        i = skip_trivia(b, end);
        if b.get(i) == Some(&b',') {
            i += 1;
        }
    }
}

/// Where the value starting at `i` ends: the `,` or closing bracket after it at its own depth.
fn value_end(b: &[u8], mut i: usize) -> Result<usize, String> {
    let mut depth = 0usize;
    let mut end = i;
    loop {
        i = skip_trivia(b, i);
        let Some(&c) = b.get(i) else { return Err("the file ends inside a value".into()) };
        match c {
            b'"' => i = skip_string(b, i + 1)?,
            b'r' if matches!(b.get(i + 1), Some(b'"' | b'#')) => i = skip_raw_string(b, i + 1)?,
            b'\'' => i = skip_char(b, i + 1)?,
            b'(' | b'[' | b'{' => {
                depth += 1;
                i += 1;
            }
            b')' | b']' | b'}' | b',' if depth == 0 => return Ok(end),
            b')' | b']' | b'}' => {
                depth -= 1;
                i += 1;
            }
            _ => i += 1,
        }
        end = i;
    }
}

/// Past spaces and comments (`// …` and nested `/* … */`).
fn skip_trivia(b: &[u8], mut i: usize) -> usize {
    loop {
        while b.get(i).is_some_and(u8::is_ascii_whitespace) {
            i += 1;
        }
        if b[i..].starts_with(b"//") {
            while b.get(i).is_some_and(|c| *c != b'\n') {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let mut depth = 0usize;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    (depth, i) = (depth + 1, i + 2);
                } else if b[i..].starts_with(b"*/") {
                    (depth, i) = (depth - 1, i + 2);
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else {
            return i;
        }
    }
}

/// Past a string whose opening quote is before `i`.
fn skip_string(b: &[u8], mut i: usize) -> Result<usize, String> {
    while let Some(&c) = b.get(i) {
        match c {
            b'\\' => i += 2,
            b'"' => return Ok(i + 1),
            _ => i += 1,
        }
    }
    Err("the file ends inside a string".into())
}

/// Past a raw string (`r#"…"#`) whose `r` is before `i`.
fn skip_raw_string(b: &[u8], mut i: usize) -> Result<usize, String> {
    let hashes = b[i..].iter().take_while(|c| **c == b'#').count();
    i += hashes + 1;
    let mut close = vec![b'"'];
    close.extend(std::iter::repeat_n(b'#', hashes));
    while i < b.len() {
        if b[i..].starts_with(&close) {
            return Ok(i + close.len());
        }
        i += 1;
    }
    Err("the file ends inside a raw string".into())
}

/// Past a character literal whose quote is before `i`.
fn skip_char(b: &[u8], i: usize) -> Result<usize, String> {
    let start = if b.get(i) == Some(&b'\\') { i + 2 } else { i + 1 };
    let end = (start..b.len()).find(|&j| b[j] == b'\'').ok_or("the file ends inside a character")?;
    Ok(end + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Interpolation, LoopMode};

    fn lane(target: &str, keys: &[(f32, f64)]) -> TrackFile {
        TrackFile {
            target: target.into(),
            interpolation: Interpolation::Step,
            repeat: LoopMode::Once,
            time_scale: 1.0,
            beats: false,
            keys: keys.iter().map(|&(t, v)| (t, RawValue::Number(v))).collect(),
        }
    }

    const SHOW: &str = r#"#![enable(implicit_some)]
// the set for Friday: "keep" this ( comment
(
    name: "friday", /* a note, ) with a bracket */
    size: (16, 16),
    layers: [(clips: [(scene: "kleinian_classic", id: "a")])],
    timeline: (
        markers: [(at: 2.0, name: "drop (big)", column: 1)],
        lanes: [(target: "layer/1.opacity", keys: [(0.0, 1.0)])], // the old lane
        chase: (start: "01:00:00:00"),
    ),
)
"#;

    #[test]
    fn saved_lanes_replace_the_old_and_keep_the_rest_of_the_file_as_written() {
        let lanes =
            [lane("layer/1.opacity", &[(0.0, 0.0), (1.0 / 60.0, 0.30000001192092896)]), lane("master.level", &[])];
        let saved = with_lanes(SHOW, &lanes).unwrap();
        assert!(saved.contains("// the set for Friday: \"keep\" this ( comment"), "{saved}");
        assert!(saved.contains("/* a note, ) with a bracket */") && saved.contains("], // the old lane"), "{saved}");
        assert!(saved.contains("(0.016666668, 0.3)"), "numbers in their shortest form: {saved}");
        assert!(
            saved.contains("\n            (target: \"layer/1.opacity\"") && saved.contains("\n        ], // the old"),
            "{saved}"
        );
        assert!(!saved.contains("keys: [(0.0, 1.0)]"), "the old lane is gone: {saved}");
        let parsed: ShowFile = ron_options().from_str(&saved).unwrap();
        assert_eq!(parsed.timeline.markers.len(), 1);
        assert_eq!(lanes_text(&parsed.timeline.lanes, 0), lanes_text(&lanes, 0));
        assert_eq!(with_lanes(&saved, &lanes).unwrap(), saved, "saving again changes nothing");
    }

    #[test]
    fn lanes_go_into_a_timeline_without_lanes_and_a_show_without_a_timeline() {
        let many: Vec<(f32, f64)> = (0..20).map(|i| (i as f32 * 0.25, f64::from(i % 3))).collect();
        let lanes = [lane("master.level", &many)];
        let bare = "(\n    name: \"bare\",\n    size: (16, 16),\n    layers: [(clips: [(scene: \"kleinian_classic\")])] // no comma\n)\n";
        let markers_only =
            SHOW.replace("        lanes: [(target: \"layer/1.opacity\", keys: [(0.0, 1.0)])], // the old lane\n", "");
        for text in [bare, markers_only.as_str()] {
            let saved = with_lanes(text, &lanes).unwrap_or_else(|e| panic!("{e}\n{text}"));
            let parsed: ShowFile = ron_options().from_str(&saved).unwrap();
            assert_eq!(lanes_text(&parsed.timeline.lanes, 0), lanes_text(&lanes, 0), "{saved}");
        }
    }

    #[test]
    fn a_file_the_scanner_cannot_follow_is_refused_not_damaged() {
        for broken in ["(name: \"x\", layers: [", "name: \"x\"", "(name \"x\")", "(timeline: 3)"] {
            assert!(with_lanes(broken, &[]).is_err(), "{broken}");
        }
    }
}
