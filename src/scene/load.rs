//! Loading a scene: by name or path, a show or a technique's own file as a scene, and RON text
//! parsed with its syntax errors located; validation is in [`super::validate`].

use super::error::{SceneError, SceneErrors};
use super::model::Scene;
use super::schema::SceneFile;
use super::validate::Validator;
use crate::assets::{AssetKind, Assets};
use crate::techniques::{self};

/// Loads a scene by name or path: an existing file path is read directly, anything else is
/// looked up in `scenes/` (disk first, then the built-in copies).
///
/// A show (`shows/<name>`, or a file whose top level has `layers`) loads as the flat scene of
/// all its clips (see [`super::show`]): every command takes shows where it takes scenes. A file a
/// technique plays (an ISF shader, `.fs`) loads as a scene of its own (see
/// [`techniques::Declarer::scene_for`]).
pub fn load_scene(assets: &Assets, name_or_path: &str) -> Result<Scene, SceneErrors> {
    if names_a_show(name_or_path) {
        return super::show::load_show(assets, name_or_path, false);
    }
    if let Some((_, declarer)) = techniques::file_technique(name_or_path) {
        // A bare shader file (ISF) plays as a generated scene (a filter over a default input).
        let text = (declarer.scene_for)(assets, name_or_path).map_err(|e| {
            SceneErrors(vec![SceneError {
                origin: e.origin,
                line: e.line as usize,
                column: e.column as usize,
                message: e.message,
            }])
        })?;
        return parse_scene_with(assets, name_or_path, &text);
    }
    let path = std::path::Path::new(name_or_path);
    let (origin, source) = if path.is_file() {
        std::fs::read_to_string(path)
            .map(|s| (path.display().to_string(), s))
            .map_err(|e| one_error(name_or_path, format!("cannot read the file: {e}")))?
    } else {
        let asset = assets.load(AssetKind::Scene, name_or_path).map_err(|m| one_error(name_or_path, m))?;
        (asset.origin, asset.source)
    };
    parse_scene_with(assets, &origin, &source)
}

/// Whether `name_or_path` is a show: under `shows/`, or a file whose top level has `layers`.
pub fn names_a_show(name_or_path: &str) -> bool {
    let path = std::path::Path::new(name_or_path);
    if path.is_file() {
        return crate::files::read_limited(path, 4 << 20)
            .is_ok_and(|bytes| super::show::is_show(&String::from_utf8_lossy(&bytes)));
    }
    name_or_path.starts_with("shows/")
}

fn one_error(origin: &str, message: String) -> SceneErrors {
    SceneErrors(vec![SceneError { origin: origin.into(), line: 1, column: 1, message }])
}

/// Parses and validates scene text; `origin` names it in errors. Files that nodes declare their
/// parameters from (ISF shaders) are found through [`Assets::discover`].
pub fn parse_scene(origin: &str, source: &str) -> Result<Scene, SceneErrors> {
    parse_scene_with(&Assets::discover(), origin, source)
}

/// [`parse_scene`] with the files nodes name found through `assets`.
pub fn parse_scene_with(assets: &Assets, origin: &str, source: &str) -> Result<Scene, SceneErrors> {
    let file: SceneFile = read_ron(origin, source)?;
    Validator::new(origin, source, assets).validate(file)
}

/// RON text as `T` (a scene or a show file), a syntax or schema error located in `origin`.
pub(crate) fn read_ron<T: serde::de::DeserializeOwned>(origin: &str, source: &str) -> Result<T, SceneErrors> {
    super::schema::ron_options().from_str(source).map_err(|e| {
        SceneErrors(vec![SceneError {
            origin: origin.into(),
            line: e.span.start.line.max(1),
            column: e.span.start.col.max(1),
            message: e.code.to_string(),
        }])
    })
}

#[cfg(test)]
mod tests {
    use super::super::edit::parse_value_override;
    use super::super::model::{MAX_NODES, MAX_REPORTED_ERRORS};
    use super::*;
    use crate::params::{ParamDecl, ParamValue};

    const GOOD: &str = r#"(
    name: "test",
    size: (64, 32),
    nodes: [
        (id: "k", technique: "kleinian", params: { "scale": 2.0, "t": (1.9, 0.1) }),
    ],
    output: "k",
    tracks: [
        (target: "k.t.y", interpolation: Linear, repeat: Loop, keys: [(0.0, 0.0), (1.0, 0.2)]),
    ],
)"#;

    fn first_error(src: &str) -> SceneError {
        parse_scene("test.ron", src).map(|_| ()).unwrap_err().0.remove(0)
    }

    #[test]
    fn a_valid_scene_resolves_params_and_tracks() {
        let scene = parse_scene("test.ron", GOOD).unwrap();
        assert_eq!(scene.nodes[0].params.get("scale"), ParamValue::Float(2.0));
        assert_eq!(scene.tracks[0].component, Some(1));
        assert_eq!(scene.dt, 1.0 / 60.0);
    }

    #[test]
    fn unknown_field_is_located_by_ron() {
        let e = first_error(&GOOD.replace("size: (64, 32),", "size: (64, 32),\n    colour: 3,"));
        assert_eq!(e.line, 4, "{e}");
        assert!(e.message.contains("colour"), "{e}");
    }

    #[test]
    fn syntax_error_is_located() {
        let e = first_error(&GOOD.replace("output: \"k\",", "output: \"k\""));
        assert!(e.line >= 7, "{e}");
    }

    #[test]
    fn unknown_param_names_the_param_and_its_line() {
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"zoom\": 2.0"));
        assert_eq!((e.line, e.column), (5, 52), "{e}");
        assert!(e.message.contains("no parameter 'zoom'") && e.message.contains("scale"), "{e}");
    }

    #[test]
    fn type_mismatch_is_an_error_not_a_default() {
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"scale\": (2.0, 1.0)"));
        assert!(e.message.contains("'scale' is a float, not a list of 2 numbers"), "{e}");
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"scale\": true"));
        assert!(e.message.contains("float"), "{e}");
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"iterations\": 2.5"));
        assert!(e.message.contains("int"), "{e}");
    }

    #[test]
    fn a_range_with_nan_or_infinity_is_a_located_error_not_a_panic() {
        for bad in ["(NaN, 3.0)", "(0.1, inf)", "(-inf, 3.0)"] {
            let src = GOOD.replace(
                "params: { \"scale\": 2.0,",
                &format!("ranges: {{ \"scale\": {bad} }}, params: {{ \"scale\": 2.0,"),
            );
            let e = first_error(&src);
            assert!(e.message.contains("two finite numbers") && e.line > 1, "{bad}: {e}");
        }
    }

    #[test]
    fn thousands_of_mistakes_report_fifty_and_count_the_rest() {
        let params: Vec<String> = (0..5000).map(|i| format!("\"nope_{i}\": 1.0")).collect();
        let src =
            GOOD.replace("params: { \"scale\": 2.0,", &format!("params: {{ {}, \"scale\": 2.0,", params.join(", ")));
        let errors = parse_scene("test.ron", &src).map(|_| ()).unwrap_err().0;
        assert_eq!(errors.len(), MAX_REPORTED_ERRORS + 1);
        assert!(errors.last().unwrap().message.contains("4950 more"), "{}", errors.last().unwrap());
    }

    #[test]
    fn a_scene_with_too_many_nodes_is_refused_at_check_time() {
        let nodes: Vec<String> = (0..=MAX_NODES).map(|i| format!("(id: \"k{i}\", technique: \"kleinian\")")).collect();
        let src = format!("(name: \"many\", size: (64, 64), nodes: [{}], output: \"k0\")", nodes.join(", "));
        let e = first_error(&src);
        assert!(e.message.contains("at most 256"), "{e}");
    }

    #[test]
    fn a_scene_asking_for_too_much_texture_memory_is_refused_at_check_time() {
        let scene = |n: usize, size: &str, msaa: u32| {
            let nodes: Vec<String> = (0..n).map(|i| format!("(id: \"k{i}\", technique: \"kleinian\")")).collect();
            format!("(name: \"big\", size: {size}, msaa: {msaa}, nodes: [{}], output: \"k0\")", nodes.join(", "))
        };
        // 100 nodes at 4K: 100 × 8.3 Mpx × 16 B = 12.4 GiB without multisampling.
        let e = first_error(&scene(100, "(3840, 2160)", 1));
        assert!(e.message.contains("12.4 GiB") && e.message.contains("at most 8 GiB"), "{e}");
        assert!(parse_scene("ok.ron", &scene(100, "(1920, 1080)", 1)).is_ok(), "100 nodes at 1080p fit (3.1 GiB)");
        // 60 nodes at 4K fit (7.4 GiB); two sets of 8 samples (1.5 GiB more) do not.
        assert!(parse_scene("ok.ron", &scene(60, "(3840, 2160)", 1)).is_ok());
        let e = first_error(&scene(60, "(3840, 2160)", 8));
        assert!(e.message.contains("msaa 8") && e.message.contains("8.9 GiB"), "{e}");
        let one = parse_scene("one.ron", &scene(100, "(64, 64)", 1)).unwrap();
        assert!(one.check_texture_budget((16384, 16384)).is_err(), "an override of the size is checked too");
        // Loaded to render at another size (`--size`), the check is made there, not at the file's.
        let at = |size| crate::assets::Assets::new(None).rendering_at(Some(size));
        let big = scene(100, "(3840, 2160)", 1);
        assert!(parse_scene_with(&at((1920, 1080)), "big.ron", &big).is_ok(), "4K in the file, rendered at 1080p");
        let small = scene(100, "(1920, 1080)", 1);
        let e = parse_scene_with(&at((3840, 2160)), "big.ron", &small).expect_err("refused").to_string();
        assert!(e.contains("at 3840x2160") && e.contains("12.4 GiB"), "{e}");
    }

    #[test]
    fn a_show_counts_the_clips_that_can_be_on_screen_at_once() {
        // 8 layers of 8 single-node clips at 4K with msaa 4: all 72 nodes would be 9.9 GiB, but a
        // layer shows one clip (two in a transition): 16 clips, the 8 blends and the master draw
        // at once, 25 nodes and two multisampled sets, 3.9 GiB.
        let clip = |l: usize, c: usize| format!(r#"(scene: "kleinian_classic", id: "c{l}_{c}")"#);
        let layer = |l: usize| format!("(clips: [{}])", (0..8).map(|c| clip(l, c)).collect::<Vec<_>>().join(", "));
        let layers: Vec<String> = (0..8).map(layer).collect();
        let show = format!(r#"(name: "wall", size: (3840, 2160), layers: [{}])"#, layers.join(", "));
        let assets = crate::assets::Assets::new(None);
        let wall = crate::scene::show::parse_show(&assets, "wall.ron", &show, false).unwrap_or_else(|e| panic!("{e}"));
        let drawn = wall.show.as_deref().unwrap().nodes_drawn_at_once(wall.nodes.len());
        assert_eq!(wall.nodes.len() - drawn, 8 * 6, "six clips of each layer cannot be on screen");
        let pixels = 3840 * 2160;
        assert_eq!(wall.texture_bytes((3840, 2160)), drawn as u64 * pixels * 16 + 2 * pixels * 48);
        // With every clip running while hidden, all of them draw: refused, naming the clips.
        let continuing = show.replace(r#"id: "c"#, r#"policy: Continue, id: "c"#);
        let e = crate::scene::show::parse_show(&assets, "wall.ron", &continuing, false).expect_err("refused");
        let e = e.to_string();
        assert!(e.contains("what can be on screen at once") && e.contains("c7_7"), "{e}");
    }

    #[test]
    fn an_unknown_option_lists_the_options() {
        let decl = ParamDecl::choice("solver", &["verlet", "xpbd"], 0, "");
        assert_eq!(parse_value_override("Bogus", &decl).unwrap_err(), "'Bogus' is not one of verlet, xpbd");
        assert_eq!(parse_value_override("xpbd", &decl), Ok(ParamValue::Enum(1)));
    }

    #[test]
    fn out_of_range_default_is_an_error() {
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"scale\": 500.0"));
        assert!(e.message.contains("outside its range"), "{e}");
    }

    #[test]
    fn unknown_technique_output_and_track_targets_are_errors() {
        assert!(
            first_error(&GOOD.replace("\"kleinian\"", "\"kleinain\"")).message.contains("unknown technique 'kleinain'")
        );
        assert!(first_error(&GOOD.replace("output: \"k\"", "output: \"q\"")).message.contains("output 'q'"));
        let e = first_error(&GOOD.replace("k.t.y", "k.scale.y"));
        assert!(e.message.contains("no component 'y'"), "{e}");
        assert_eq!(e.line, 9, "{e}");
        assert!(first_error(&GOOD.replace("k.t.y", "k.tt")).message.contains("no parameter 'tt'"));
    }

    #[test]
    fn every_error_is_reported_not_just_the_first() {
        let src = GOOD.replace("\"scale\": 2.0", "\"zoom\": 2.0").replace("output: \"k\"", "output: \"q\"");
        assert_eq!(parse_scene("test.ron", &src).map(|_| ()).unwrap_err().0.len(), 2);
    }

    #[test]
    fn cli_overrides_are_typed_and_clamped() {
        let mut scene = parse_scene("test.ron", GOOD).unwrap();
        scene.set_from_str("k.samples=10").unwrap();
        scene.set_from_str("k.t=1.5,0.25").unwrap();
        scene.set_from_str("k.iterations=99999").unwrap();
        let p = &scene.nodes[0].params;
        assert_eq!((p.int("samples"), p.vec2("t"), p.int("iterations")), (10, [1.5, 0.25], 5000));
        assert!(scene.set_from_str("k.samples=lots").unwrap_err().contains("not a number"));
        assert!(scene.set_from_str("k.t=1").unwrap_err().contains("vec2"));
        assert!(scene.set_from_str("x.t=1").unwrap_err().contains("no node 'x'"));
    }

    #[test]
    fn every_bundled_scene_is_valid() {
        let assets = Assets::new(None);
        for name in assets.names(AssetKind::Scene) {
            load_scene(&assets, &name).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}
