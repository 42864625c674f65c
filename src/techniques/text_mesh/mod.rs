//! Text as triangulated glyph outlines [UGP4 ch.5 applied]: the `text` parameter (settable over
//! OSC, e.g. a TouchOSC text field) is laid out in Ubuntu Light (bundled with egui, Ubuntu Font
//! Licence), each glyph's quadratic outline is flattened and all rings are triangulated together
//! — counters such as the holes of "A", "B", "8" come from nesting. Drawn like the drawing scene:
//! UV checker fill and wireframe (shader `polygon_draw.wgsl`).

use ttf_parser::{Face, OutlineBuilder};

use crate::geometry::outline::RingBuilder;
use crate::geometry::triangulate::{Mesh2D, Triangulator};
use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue, Text};
use crate::time::FrameTime;

use super::mesh2d_draw::{DrawStyle, Renderer};
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "text_mesh",
    chapter: "5: Triangulation by ear clipping (glyph outlines)",
    summary: "a text parameter as triangulated glyph outlines, live",
    params: Settings::decls,
    inputs: &[],
    shaders: &["polygon_draw.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The bundled font.
pub fn font() -> Face<'static> {
    Face::parse(epaint_default_fonts::UBUNTU_LIGHT, 0).expect("the bundled font parses")
}

crate::technique_params! {
    /// What a text node reads each frame.
    pub struct Settings {
        /// the text to mesh (one line)
        text: Text = |n, doc| ParamDecl::text(n, "indra 808", doc),
        /// em size in world units
        size: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(2.0), Some((0.05, 20.0)), doc).with_unit("u"),
        /// curve flattening tolerance
        tolerance: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.002), Some((0.0001, 0.2)), doc).with_unit("u"),
        /// draw the triangle edges over the fill
        wireframe: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
        /// checker cells across the UV range
        checker: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(8), Some((1.0, 64.0)), doc),
        /// half the view height in world units
        view_size: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(2.5), Some((0.5, 100.0)), doc),
    }
}

/// Forwards a glyph's outline into a [`RingBuilder`], scaled and offset into world units.
struct GlyphSink<'a> {
    rings: &'a mut RingBuilder,
    scale: f64,
    offset: [f64; 2],
}

impl GlyphSink<'_> {
    fn at(&self, x: f32, y: f32) -> [f64; 2] {
        [self.offset[0] + f64::from(x) * self.scale, self.offset[1] + f64::from(y) * self.scale]
    }
}

impl OutlineBuilder for GlyphSink<'_> {
    fn move_to(&mut self, x: f32, y: f32) {
        let p = self.at(x, y);
        self.rings.move_to(p);
    }
    fn line_to(&mut self, x: f32, y: f32) {
        let p = self.at(x, y);
        self.rings.line_to(p);
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        let (c, p) = (self.at(x1, y1), self.at(x, y));
        self.rings.quad_to(c, p);
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        let (c1, c2, p) = (self.at(x1, y1), self.at(x2, y2), self.at(x, y));
        self.rings.cubic_to(c1, c2, p);
    }
    fn close(&mut self) {
        self.rings.close();
    }
}

/// The outline rings of `text` set in `face` at em size `size`, centred on the origin.
pub fn text_rings(face: &Face<'_>, text: &str, size: f64, tolerance: f64) -> Vec<Vec<[f64; 2]>> {
    let scale = size / f64::from(face.units_per_em());
    let mut builder = RingBuilder::new(tolerance);
    let mut pen = 0.0;
    for c in text.chars() {
        let Some(glyph) = face.glyph_index(c) else { continue };
        let mut sink = GlyphSink { rings: &mut builder, scale, offset: [pen, 0.0] };
        face.outline_glyph(glyph, &mut sink);
        pen += f64::from(face.glyph_hor_advance(glyph).unwrap_or(0)) * scale;
    }
    let mut rings = builder.finish();
    // Centre the ink box.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in rings.iter().flatten() {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if lo[0].is_finite() {
        let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        rings.iter_mut().flatten().for_each(|p| *p = [p[0] - centre[0], p[1] - centre[1]]);
    }
    rings
}

/// A text node.
pub struct TextMesh {
    renderer: Renderer,
    face: Face<'static>,
    triangulator: Triangulator,
    /// (text, size, tolerance) the mesh was built from.
    built: Option<(Text, f32, f32)>,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(TextMesh {
        renderer: Renderer::new(setup)?,
        face: font(),
        triangulator: Triangulator::new(),
        built: None,
        messages: Vec::new(),
    }))
}

impl TextMesh {
    fn rebuild(&mut self, p: &Settings) {
        let key = (p.text, p.size, p.tolerance);
        let text = p.text;
        if self.built == Some(key) {
            return;
        }
        self.built = Some(key);
        let rings = text_rings(&self.face, text.as_str(), f64::from(key.1), f64::from(key.2));
        let mesh = self.triangulator.rings(&rings).unwrap_or_else(|e| {
            self.messages.push(e.to_string());
            Mesh2D::default()
        });
        self.messages.extend(mesh.report.warnings());
        self.renderer.upload(&mesh, &[]);
    }
}

impl Technique for TextMesh {
    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let settings = Settings::read(params);
        self.rebuild(&settings);
        let style =
            DrawStyle { wireframe: settings.wireframe, checker: settings.checker, view_size: settings.view_size };
        self.renderer.add_pass(graph, "text_mesh", &style, time)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangulate::triangulate;

    #[test]
    fn glyph_outlines_triangulate_exactly_with_counters_as_holes() {
        let face = font();
        let rings = text_rings(&face, "ABO 808 &@%", 2.0, 0.002);
        let mesh = triangulate(&rings).unwrap();
        assert!(mesh.report.dropped.is_empty(), "{:?}", mesh.report.dropped);
        assert!(mesh.report.area_deviation() < 1e-9, "{:?}", mesh.report);
        // A, B, O, 8, 0, 8, &, @, % have counters: at least 11 holes among them.
        assert!(mesh.report.holes >= 11, "{} holes", mesh.report.holes);
        let n: usize = rings.iter().map(Vec::len).sum();
        assert!(mesh.triangle_count() <= n + 2 * mesh.report.holes);
    }

    #[test]
    fn unknown_characters_are_skipped_and_empty_text_is_empty() {
        let face = font();
        assert!(text_rings(&face, "", 1.0, 0.01).is_empty());
        assert!(text_rings(&face, "\u{E000}", 1.0, 0.01).is_empty());
    }
}

#[cfg(test)]
mod render_tests;
