//! The surface's URL as a QR code, for a phone's camera: drawn in the terminal with half-block
//! characters, and as a grid of modules the panel paints.

use qrcode::{EcLevel, QrCode};

/// The dark modules of `text`'s QR code, row by row (`true`: dark), with no quiet zone; `None`
/// when the text is too long for a QR code.
pub fn modules(text: &str) -> Option<Vec<Vec<bool>>> {
    let code = QrCode::with_error_correction_level(text.as_bytes(), EcLevel::L).ok()?;
    let width = code.width();
    let colors = code.into_colors();
    Some(colors.chunks(width).map(|row| row.iter().map(|c| *c == qrcode::Color::Dark).collect()).collect())
}

/// `text`'s QR code in the terminal: two module rows per line (`▀ ▄ █`), dark on light with a
/// two-module quiet zone, since terminals differ in their colours and a reader needs light around.
pub fn terminal(text: &str) -> Option<String> {
    let rows = modules(text)?;
    const QUIET: usize = 2;
    let size = rows.len() + 2 * QUIET;
    let dark = |x: usize, y: usize| {
        (QUIET..size - QUIET).contains(&x) && (QUIET..size - QUIET).contains(&y) && rows[y - QUIET][x - QUIET]
    };
    let mut out = String::new();
    for y in (0..size).step_by(2) {
        for x in 0..size {
            // Light is drawn (a block), dark is the terminal's background: a code on a dark
            // terminal then reads as dark modules on light, as readers want.
            let (top, bottom) = (!dark(x, y), y + 1 < size && !dark(x, y + 1));
            out.push(match (top, bottom) {
                (true, true) => '█',
                (true, false) => '▀',
                (false, true) => '▄',
                (false, false) => ' ',
            });
        }
        out.push('\n');
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_url_becomes_a_square_code_with_finder_patterns() {
        let rows = modules("http://192.168.1.20:8080/?token=0123456789abcdef0123456789abcdef").unwrap();
        let n = rows.len();
        assert!(n >= 21 && rows.iter().all(|r| r.len() == n), "{n}");
        // The three finder patterns: dark 7×7 rings in three corners.
        for (x, y) in [(0, 0), (n - 7, 0), (0, n - 7)] {
            assert!((0..7).all(|i| rows[y][x + i] && rows[y + 6][x + i] && rows[y + i][x] && rows[y + i][x + 6]));
            assert!(!rows[y + 1][x + 1] && rows[y + 3][x + 3]);
        }
        let text = terminal("http://x/").unwrap();
        assert_eq!(text.lines().count(), (modules("http://x/").unwrap().len() + 4).div_ceil(2));
        assert!(modules(&"x".repeat(8000)).is_none(), "too long for any QR code");
    }
}
