//! `indra list`, `--list-ndi` and `--list-cameras`: what a scene or node can name.

use indra::assets::{AssetKind, Assets};
use indra::scene::load_scene;

/// Lists scenes and shows with their nodes and parameters.
pub fn list(assets: &Assets) -> Result<(), String> {
    let scenes = assets.names(AssetKind::Scene).into_iter();
    let shows = assets.names(AssetKind::Show).into_iter().map(|n| format!("shows/{n}"));
    for name in scenes.chain(shows) {
        match load_scene(assets, &name) {
            Err(e) => say!("{name}: INVALID\n{e}\n"),
            Ok(scene) => {
                let stem = name.trim_end_matches(".ron");
                say!("{stem} — {} ({}x{}): {}", scene.name, scene.size.0, scene.size.1, scene.description);
                if let Some(show) = &scene.show {
                    list_show(show);
                }
                for (i, node) in scene.nodes.iter().enumerate() {
                    say!("  node {} ({})", node.id, node.technique.name);
                    for (p, decl) in node.params.decls().iter().enumerate() {
                        let animated = scene.tracks.iter().any(|t| t.node == i && t.param == p);
                        let range = decl.range.map(|(lo, hi)| format!(" [{lo} … {hi}]")).unwrap_or_default();
                        say!(
                            "    /indra/{}/{:<18} {:<6} = {}{range}{}",
                            node.id,
                            decl.name,
                            decl.ty(),
                            decl.format(&node.params.value_at(p)),
                            if animated { "  (animated)" } else { "" }
                        );
                    }
                }
                say!();
            }
        }
    }
    say!(
        "ISF shaders and gl-transitions (technique \"isf\", params: {{ \"file\": PATH }}, or a show's transition \
         kind or effect; each parameter at /indra/<node>/<name>):"
    );
    for name in indra::techniques::isf::shader_names(assets) {
        match indra::techniques::isf::describe(assets, &name) {
            Ok(line) => say!("  {name} — {line}"),
            Err(e) => say!("  {name}: INVALID {e}"),
        }
    }
    Ok(())
}

/// A show's layers, clips (with their trigger addresses) and cues.
fn list_show(show: &indra::scene::show::Show) {
    for (l, layer) in show.layers.iter().enumerate() {
        say!("  layer {} '{}': /indra/layer/{}/opacity, /indra/layer/{}/blend", l + 1, layer.name, l + 1, l + 1);
        for (c, &clip) in layer.clips.iter().enumerate() {
            let clip = &show.clips[clip];
            say!("    clip {} {} ({}): /indra/layer/{}/clip/{}/connect", c + 1, clip.id, clip.scene, l + 1, c + 1);
        }
        for (k, _) in layer.effects.iter().enumerate() {
            say!("    effect {}: /indra/layer/{}/fx/{}/<param>, …/bypass, …/mix", k + 1, l + 1, k + 1);
        }
    }
    for (k, _) in show.master_effects.iter().enumerate() {
        say!("  master effect {}: /indra/master/fx/{}/<param>, …/bypass, …/mix", k + 1, k + 1);
    }
    for (i, cue) in show.cues.iter().enumerate() {
        say!("  cue {} {}", i + 1, cue.name);
    }
}

/// `indra --list-ndi`: the NDI sources an `ndi` node can name.
pub fn list_ndi() -> Result<(), String> {
    let sources = indra::media::ndi::list_sources(std::time::Duration::from_secs(2))?;
    if sources.is_empty() {
        println!("no NDI sources seen within 2 s (senders on other machines: see the README's NDI section)");
    }
    for source in sources {
        println!("{}  {}", source.name, source.url);
    }
    Ok(())
}

/// `indra --list-cameras`: the V4L2 devices a `camera` node can name.
pub fn list_cameras() -> Result<(), String> {
    let cameras = indra::media::camera::list_cameras();
    if cameras.is_empty() {
        println!(
            "no cameras found (no V4L2 devices under /sys/class/video4linux); `device: \"test\"` plays a test pattern"
        );
    }
    for camera in cameras {
        println!("{}  {}", camera.device.display(), camera.name);
    }
    Ok(())
}
