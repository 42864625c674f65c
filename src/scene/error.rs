//! Scene errors located in their file.

use std::fmt;

/// One problem in a scene file, with its place.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// The file (path or `<embedded>/scenes/…`).
    pub origin: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// What is wrong and, where it helps, what is allowed.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.origin, self.line, self.column, self.message)
    }
}

/// Every problem found in one scene file (at least one).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneErrors(pub Vec<SceneError>);

impl fmt::Display for SceneErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lines: Vec<String> = self.0.iter().map(ToString::to_string).collect();
        f.write_str(&lines.join("\n"))
    }
}

impl std::error::Error for SceneErrors {}

/// Finds where a semantic error sits: each anchor is searched after the previous one, and the
/// position of the last found is returned (1-based line and column). Serde gives positions for
/// syntax and unknown fields; checks that need the technique registry locate themselves this way.
pub(crate) fn locate(source: &str, anchors: &[&str]) -> (usize, usize) {
    let mut at = 0;
    let mut found = 0;
    for anchor in anchors {
        if let Some(i) = source[at..].find(anchor) {
            found = at + i;
            at = found + anchor.len();
        }
    }
    let before = &source[..found];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::locate;

    #[test]
    fn locate_follows_anchors_in_order() {
        let src = "a: 1,\nnodes: [\n  (id: \"x\", params: {\"scale\": 2}),\n]";
        assert_eq!(locate(src, &["\"x\"", "\"scale\""]), (3, 22));
        assert_eq!(locate(src, &["nodes"]), (2, 1));
        assert_eq!(locate(src, &["missing"]), (1, 1));
    }
}
