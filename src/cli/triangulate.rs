//! `indra triangulate <file>`: reads rings (JSON or SVG), triangulates them and reports count,
//! area deviation and time; `--out` writes the mesh as JSON or Wavefront OBJ.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indra::geometry::outline::svg_path_rings;
use indra::geometry::triangulate::{Mesh2D, Triangulator};

/// Arguments of `indra triangulate`.
#[derive(clap::Args)]
pub struct TriangulateArgs {
    /// Rings as JSON (`[[[x, y], …], …]`, any orientation and nesting), an SVG file (every
    /// `<path d=…>`), or bare SVG path data.
    pub file: PathBuf,
    /// Write the mesh: `.obj` for Wavefront OBJ, anything else JSON (positions, indices, uvs).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Curve flattening tolerance for SVG input, in path units.
    #[arg(long, default_value_t = 0.1)]
    pub tolerance: f64,
    /// How rings are read: `nesting` (any order and orientation; rings inside rings are holes,
    /// rings inside holes are filled again; rings that cross themselves are cut; single points
    /// are Steiner points of the area around them) or `earcut` (the first ring is the outer
    /// ring, every other ring a hole, single points Steiner points — GIS and font data).
    #[arg(long, value_enum, default_value_t = Layout::Nesting)]
    pub layout: Layout,
}

/// How `indra triangulate` reads its rings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Layout {
    /// By nesting, in any order and orientation (the book's DrawTest).
    Nesting,
    /// First ring outer, the rest holes, single points Steiner points (earcut's layout).
    Earcut,
}

/// Runs the command.
pub fn triangulate(args: &TriangulateArgs) -> Result<(), String> {
    let text = std::fs::read_to_string(&args.file).map_err(|e| format!("cannot read {}: {e}", args.file.display()))?;
    let rings = read_rings(&text, args.tolerance).map_err(|e| format!("{}: {e}", args.file.display()))?;
    let mut triangulator = Triangulator::new();
    let start = Instant::now();
    let mesh = match args.layout {
        Layout::Nesting => triangulator.rings(&rings),
        Layout::Earcut => triangulator.outer_and_holes(&rings),
    }
    .map_err(|e| format!("{}: {e}", args.file.display()))?;
    let elapsed = start.elapsed();
    let report = &mesh.report;
    println!(
        "{} rings ({} filled, {} holes, {} Steiner points), {} vertices → {} triangles",
        rings.len(),
        report.outers,
        report.holes,
        report.steiner,
        mesh.positions.len(),
        mesh.triangle_count()
    );
    println!(
        "area deviation {:.3e} (polygon {:.6}, triangles {:.6})",
        report.area_deviation(),
        report.polygon_area,
        report.triangle_area
    );
    println!("time {:.3} ms", elapsed.as_secs_f64() * 1e3);
    for warning in report.warnings() {
        println!("warning: {warning}");
    }
    if let Some(out) = &args.out {
        write_mesh(out, &mesh).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

/// Rings from JSON, an SVG document or SVG path data.
fn read_rings(text: &str, tolerance: f64) -> Result<Vec<Vec<[f64; 2]>>, String> {
    let trimmed = text.trim_start();
    if trimmed.starts_with('[') {
        return serde_json::from_str(text).map_err(|e| format!("JSON rings (an array of rings of [x, y]): {e}"));
    }
    if trimmed.starts_with('<') {
        let mut rings = Vec::new();
        for data in path_attributes(text) {
            rings.extend(svg_path_rings(data, tolerance)?);
        }
        if rings.is_empty() {
            return Err("no <path d=\"…\"> in the SVG document".into());
        }
        return Ok(rings);
    }
    svg_path_rings(text, tolerance)
}

/// The values of every ` d="…"` / ` d='…'` attribute in an SVG document.
fn path_attributes(svg: &str) -> impl Iterator<Item = &str> {
    svg.match_indices(" d=").filter_map(move |(at, _)| {
        let rest = &svg[at + 3..];
        let quote = rest.chars().next().filter(|c| *c == '"' || *c == '\'')?;
        let body = &rest[1..];
        body.find(quote).map(|end| &body[..end])
    })
}

fn write_mesh(path: &Path, mesh: &Mesh2D) -> std::io::Result<()> {
    use std::fmt::Write;
    let mut text = String::new();
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) {
        let _ = writeln!(text, "# indra triangulate: {} triangles", mesh.triangle_count());
        for p in &mesh.positions {
            let _ = writeln!(text, "v {} {} 0", p[0], p[1]);
        }
        for uv in &mesh.uvs {
            let _ = writeln!(text, "vt {} {}", uv[0], uv[1]);
        }
        for t in mesh.indices.chunks_exact(3) {
            let _ = writeln!(text, "f {0}/{0} {1}/{1} {2}/{2}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
    } else {
        let json = serde_json::json!({ "positions": mesh.positions, "indices": mesh.indices, "uvs": mesh.uvs });
        text = json.to_string();
    }
    std::fs::write(path, text)
}
