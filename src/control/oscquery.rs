//! OSCQuery: an HTTP endpoint serving the JSON address tree (FULL_PATH, CONTENTS, TYPE, RANGE,
//! VALUE, ACCESS, DESCRIPTION, per the OSCQuery proposal by Vidvox) and HOST_INFO, so
//! TouchOSC-style clients discover every parameter; the LISTEN extension over a WebSocket on the
//! same port (see [`super::listen`]); and DNS-SD advertisement (see [`super::discovery`]). The
//! render loop publishes snapshots and queues changes; the server threads only read them.

use std::sync::{Arc, RwLock};

use rosc::OscMessage;
use serde_json::{Map, Value, json};

use super::address::param_address;
use super::discovery::Advertisement;
use super::http::{HttpServer, Reply, Request, Routes};
use super::listen::Listeners;
use super::osc::OscInlet;
use super::site::SiteRules;
use super::web::WebOptions;
use crate::params::{ParamDecl, ParamType, ParamValue};
use crate::scene::SceneView;

/// The OSC type tag string of a parameter type.
fn type_tag(ty: ParamType) -> &'static str {
    match ty {
        ParamType::Float => "f",
        ParamType::Int => "i",
        ParamType::Bool => "T",
        ParamType::Vec2 => "ff",
        ParamType::Vec3 => "fff",
        ParamType::Vec4 | ParamType::Color => "ffff",
        ParamType::Enum | ParamType::Text => "s",
        ParamType::Trigger => "I",
    }
}

fn value_json(value: &ParamValue, decl: &ParamDecl) -> Value {
    match value {
        ParamValue::Int(i) => json!([i]),
        ParamValue::Bool(b) => json!([b]),
        ParamValue::Enum(_) => json!([decl.format(value)]),
        ParamValue::Text(t) => json!([t.as_str()]),
        ParamValue::Trigger(_) => json!([]),
        other => json!(&*other.components()),
    }
}

fn range_json(decl: &ParamDecl) -> Option<Value> {
    if decl.ty() == ParamType::Enum {
        return Some(json!([{ "VALS": decl.options }]));
    }
    let (lo, hi) = decl.range?;
    Some(Value::Array(vec![json!({ "MIN": lo, "MAX": hi }); decl.ty().components()]))
}

/// The control a value asks for where its type tag does not say (an extension: OSCQuery clients
/// ignore attributes they do not know). `color`: four floats that are an RGBA colour; `xy`: a
/// 2-D point; `text`: free text.
fn widget(ty: ParamType) -> Option<&'static str> {
    match ty {
        ParamType::Color => Some("color"),
        ParamType::Vec2 => Some("xy"),
        ParamType::Text => Some("text"),
        _ => None,
    }
}

/// The engine's own controls: presets (recall with morph seconds, save) and tempo (BPM and tap).
fn engine_leaves(root: &mut Map<String, Value>, presets: &[String], bpm: f64) {
    let (lo, hi) = crate::params::lfo::BPM_RANGE;
    let preset = json!({ "FULL_PATH": "/indra/preset", "CONTENTS": {
        "recall": { "FULL_PATH": "/indra/preset/recall", "TYPE": "sf", "ACCESS": 2,
            "RANGE": [{ "VALS": presets }, { "MIN": 0.0, "MAX": 60.0 }],
            "DESCRIPTION": "recall a preset, morphing over the seconds given" },
        "save": { "FULL_PATH": "/indra/preset/save", "TYPE": "s", "ACCESS": 2,
            "DESCRIPTION": "save the current values as a preset of this name" },
    }});
    let tempo = json!({ "FULL_PATH": "/indra/tempo", "CONTENTS": {
        "bpm": { "FULL_PATH": "/indra/tempo/bpm", "TYPE": "f", "ACCESS": 3, "VALUE": [bpm],
            "RANGE": [{ "MIN": lo, "MAX": hi }], "UNIT": ["BPM"], "DESCRIPTION": "the show's tempo" },
        "tap": { "FULL_PATH": "/indra/tempo/tap", "TYPE": "I", "ACCESS": 2, "DESCRIPTION": "tap tempo: tap on the beat" },
    }});
    root.insert("preset".into(), preset);
    root.insert("tempo".into(), tempo);
}

/// The whole address tree of `instance` with current values. Node ids with `/` (a show's
/// `<clip>/<node>`, `layer/<n>`) nest as their addresses do. A show's tree holds its layers, the
/// master, the trigger addresses of every clip, column and cue, and the parameters of the clips
/// on screen — a clip change alters it (see [`shown_clips`]); a hidden clip's parameters still
/// take writes at their addresses. `presets` are the names `/indra/preset/recall` offers.
pub fn tree(instance: SceneView<'_>, presets: &[String]) -> Value {
    let mut root = Map::new();
    engine_leaves(&mut root, presets, instance.tempo.bpm);
    for (n, node) in instance.scene.nodes.iter().enumerate() {
        if let Some((show, state)) = instance.show
            && show.clip_of(n).is_some_and(|c| !state.visible(c))
        {
            continue;
        }
        let params = instance.params(n);
        let mut contents = Map::new();
        for (p, decl) in params.decls().iter().enumerate() {
            let mut leaf = Map::new();
            leaf.insert("FULL_PATH".into(), json!(param_address(&node.id, &decl.name)));
            leaf.insert("TYPE".into(), json!(type_tag(decl.ty())));
            leaf.insert("ACCESS".into(), json!(if decl.ty() == ParamType::Trigger { 2 } else { 3 }));
            leaf.insert("VALUE".into(), value_json(&params.target_at(p), decl));
            if let Some(range) = range_json(decl) {
                leaf.insert("RANGE".into(), range);
            }
            if !decl.unit.is_empty() {
                leaf.insert("UNIT".into(), json!(vec![decl.unit.as_str(); decl.ty().components()]));
            }
            if let Some(widget) = widget(decl.ty()) {
                leaf.insert("WIDGET".into(), json!(widget));
            }
            leaf.insert("DESCRIPTION".into(), json!(decl.doc));
            contents.insert(decl.name.clone(), Value::Object(leaf));
        }
        let container = container_at(&mut root, &node.id, "/indra");
        container.insert("DESCRIPTION".into(), json!(node.technique.summary));
        contents_of(container).extend(contents);
    }
    if let Some((show, state)) = instance.show {
        let trigger = |path: String, description: String| json!({ "FULL_PATH": format!("/indra/{path}"), "TYPE": "I", "ACCESS": 2, "DESCRIPTION": description });
        let mut put = |path: String, leaf: Value| {
            let (parent, name) = path.rsplit_once('/').unwrap_or(("", &path));
            let name = name.to_string();
            let container =
                if parent.is_empty() { &mut root } else { contents_of(container_at(&mut root, parent, "/indra")) };
            container.insert(name, leaf);
        };
        for (l, layer) in show.layers.iter().enumerate() {
            for (c, &clip) in layer.clips.iter().enumerate() {
                let path = format!("layer/{}/clip/{}/connect", l + 1, c + 1);
                put(path.clone(), trigger(path, format!("play {} on {}", show.clips[clip].id, layer.name)));
            }
            let path = format!("layer/{}/clear", l + 1);
            put(path.clone(), trigger(path, format!("empty {}", layer.name)));
            // Read-only: the clip the layer plays, from 1 (0: none), for controllers to show.
            let playing = state.playing(l).and_then(|c| layer.clips.iter().position(|&k| k == c)).map_or(0, |c| c + 1);
            let path = format!("layer/{}/playing", l + 1);
            let description = format!("the clip {} plays, from 1 (0: none)", layer.name);
            put(
                path.clone(),
                json!({ "FULL_PATH": format!("/indra/{path}"), "TYPE": "i", "ACCESS": 1, "VALUE": [playing], "DESCRIPTION": description }),
            );
        }
        // Each chain's edits (a bypass is each effect's own `bypass` parameter in the tree).
        let chains = show.layers.iter().enumerate().map(|(l, layer)| (format!("layer/{}", l + 1), layer.effects.len()));
        for (owner, len) in chains.chain([("master".to_string(), show.master_effects.len())]) {
            let mut add = json!({ "FULL_PATH": format!("/indra/{owner}/fx/add"), "TYPE": "s", "ACCESS": 2,
                "DESCRIPTION": "add an effect: an ISF filter file or a technique that takes an image" });
            if let Some(names) = crate::scene::show::effects::library::names() {
                add["RANGE"] = json!([{ "VALS": names }]);
            }
            put(format!("{owner}/fx/add"), add);
            if len > 0 {
                let range = json!({ "MIN": 1, "MAX": len });
                put(
                    format!("{owner}/fx/remove"),
                    json!({ "FULL_PATH": format!("/indra/{owner}/fx/remove"),
                    "TYPE": "i", "ACCESS": 2, "RANGE": [range], "DESCRIPTION": "remove effect i (from 1)" }),
                );
                put(
                    format!("{owner}/fx/move"),
                    json!({ "FULL_PATH": format!("/indra/{owner}/fx/move"),
                    "TYPE": "ii", "ACCESS": 2, "RANGE": [range, range], "DESCRIPTION": "move effect i to place j" }),
                );
            }
        }
        for (c, name) in show.columns.iter().enumerate() {
            let path = format!("column/{}/connect", c + 1);
            put(path.clone(), trigger(path, format!("play column {name}")));
        }
        if !show.cues.is_empty() {
            put("cue/go".into(), trigger("cue/go".into(), "the next cue".into()));
            put("cue/back".into(), trigger("cue/back".into(), "the previous cue".into()));
            let names: Vec<&str> = show.cues.iter().map(|c| c.name.as_str()).collect();
            let goto = json!({ "FULL_PATH": "/indra/cue/goto", "TYPE": "s", "ACCESS": 2,
                "RANGE": [{ "VALS": names }], "DESCRIPTION": "a cue by name (or its number, from 1)" });
            put("cue/goto".into(), goto);
        }
    }
    json!({
        "FULL_PATH": "/",
        "CONTENTS": { "indra": { "FULL_PATH": "/indra", "CONTENTS": root, "DESCRIPTION": instance.scene.name } }
    })
}

/// The clips a show's tree holds now (those on screen); empty for a scene.
pub fn shown_clips(instance: SceneView<'_>) -> Vec<usize> {
    instance.show.map_or_else(Vec::new, |(show, state)| (0..show.clips.len()).filter(|&c| state.visible(c)).collect())
}

/// The container at `path` (segments under `parent`, a full path) in `map`, made as needed.
fn container_at<'m>(map: &'m mut Map<String, Value>, path: &str, parent: &str) -> &'m mut Map<String, Value> {
    let (head, rest) = path.split_once('/').map_or((path, None), |(h, r)| (h, Some(r)));
    let full = format!("{parent}/{head}");
    let entry = map.entry(head.to_string()).or_insert_with(|| json!({ "FULL_PATH": full.clone(), "CONTENTS": {} }));
    if !entry.is_object() {
        *entry = json!({ "FULL_PATH": full.clone(), "CONTENTS": {} });
    }
    let object = entry.as_object_mut().expect("made an object above");
    match rest {
        None => object,
        Some(rest) => container_at(contents_of(object), rest, &full),
    }
}

/// The CONTENTS map of a container (made if missing).
fn contents_of(container: &mut Map<String, Value>) -> &mut Map<String, Value> {
    let contents = container.entry("CONTENTS").or_insert_with(|| json!({}));
    if !contents.is_object() {
        *contents = json!({});
    }
    contents.as_object_mut().expect("made an object above")
}

/// The HOST_INFO reply.
pub fn host_info(osc_port: u16) -> Value {
    json!({
        "NAME": "indra",
        "OSC_PORT": osc_port,
        "OSC_TRANSPORT": "UDP",
        "EXTENSIONS": {
            "ACCESS": true, "VALUE": true, "RANGE": true, "DESCRIPTION": true, "TYPE": true,
            "UNIT": true, "LISTEN": true, "PATH_CHANGED": true
        }
    })
}

/// The node of `tree` at `path` (`/indra/limit_set/scale`), if it exists.
pub fn subtree<'a>(tree: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('/').filter(|s| !s.is_empty()).try_fold(tree, |node, part| node.get("CONTENTS")?.get(part))
}

/// The OSCQuery endpoint: the published tree over HTTP, value changes to listening controllers
/// over WebSockets, and its advertisement over mDNS.
pub struct OscQueryServer {
    /// The published tree; `None` until the first frame publishes one.
    snapshot: Arc<RwLock<Option<Value>>>,
    listeners: Arc<Listeners>,
    /// The scene changed: publish and announce it after the next frame.
    path_changed: bool,
    /// The show's clips the published tree holds.
    shown: Vec<usize>,
    /// The preset names the tree offers.
    presets: Vec<String>,
    /// The tempo last sent to listeners (it is no parameter, so [`ParamChanges`] misses it).
    ///
    /// [`ParamChanges`]: super::feedback::ParamChanges
    bpm: Option<f64>,
    server: HttpServer,
    /// Kept for its lifetime: dropping it withdraws the advertisement.
    _advertisement: Option<Advertisement>,
}

impl OscQueryServer {
    /// Serves on `addr` (port 0 picks one), naming `osc_port` in HOST_INFO and advertising both
    /// over mDNS unless `addr` is loopback. The server has hard limits (see [`super::http`]):
    /// no request can exhaust memory or hold up the others. mDNS that cannot start is logged.
    pub fn start(addr: &str, osc_port: u16) -> Result<Self, String> {
        Self::start_with(addr, osc_port, None, &SiteRules::default())
    }

    /// [`OscQueryServer::start`], serving the browser control surface too when `surface` is
    /// given: its page, and OSC from the WebSocket sessions it admits into the inlet; `sites`
    /// adds host names and third-party origins to those answered.
    pub fn start_with(
        addr: &str,
        osc_port: u16,
        surface: Option<(WebOptions, OscInlet)>,
        sites: &SiteRules,
    ) -> Result<Self, String> {
        let snapshot: Arc<RwLock<Option<Value>>> = Arc::default();
        let tree = snapshot.clone();
        let web = surface.as_ref().map(|(options, _)| options.clone());
        let handler = Arc::new(move |request: &Request<'_>| {
            if let Some(reply) = web.as_ref().and_then(|web| web.reply(request)) {
                return reply;
            }
            if request.query().contains("HOST_INFO") {
                return Reply::json(200, host_info(osc_port).to_string());
            }
            let Ok(tree) = tree.read() else { return Reply::status(503) };
            // Until the show has built its scene there is no tree: a controller connecting at
            // start-up is told to come back, not shown an empty show.
            match tree.as_ref().map(|t| subtree(t, request.path())) {
                None => Reply::status(503),
                Some(Some(v)) => Reply::json(200, v.to_string()),
                Some(None) => Reply::status(404),
            }
        });
        let listeners = Arc::new(Listeners::default());
        let sessions = listeners.clone();
        let max_sockets = surface.as_ref().map_or(super::http::MAX_SOCKETS, |(web, _)| web.sessions);
        let socket = Arc::new(move |request: &Request<'_>, origin, socket| {
            let control = surface.as_ref().filter(|(web, _)| web.controls(request, origin)).map(|(_, inlet)| inlet);
            sessions.serve(socket, control);
        });
        let routes = Routes { get: handler, socket: Some(socket), max_sockets, sites: sites.clone() };
        let server = HttpServer::start(addr, "oscquery", routes)?;
        let local = server.local_addr();
        log::info!("OSCQuery on http://{local}/");
        let advertisement = match Advertisement::start(&format!("indra-{}", local.port()), local, osc_port) {
            Ok(a) => Some(a),
            Err(e) if local.ip().is_loopback() => {
                log::info!("{e}");
                None
            }
            Err(e) => {
                log::warn!("{e}; controllers must be given the address by hand");
                None
            }
        };
        Ok(Self {
            snapshot,
            listeners,
            path_changed: false,
            shown: Vec::new(),
            presets: Vec::new(),
            bpm: None,
            server,
            _advertisement: advertisement,
        })
    }

    /// The bound address.
    pub fn local_addr(&self) -> std::net::SocketAddr {
        self.server.local_addr()
    }

    /// Publishes the current tree.
    pub fn publish(&self, instance: SceneView<'_>) {
        let t = tree(instance, &self.presets);
        if let Ok(mut s) = self.snapshot.write() {
            *s = Some(t);
        }
    }

    /// Whether a controller is connected for LISTEN.
    pub fn listening(&self) -> bool {
        self.listeners.any()
    }

    /// After a frame: publishes the tree when `publish` asks (or the scene changed, which is
    /// then announced to listening controllers) and queues `changes` (the frame's, see
    /// [`super::feedback::ParamChanges`]) for the controllers listening to them. Returns how many
    /// messages were queued.
    pub fn after_frame(&mut self, instance: SceneView<'_>, publish: bool, changes: &[OscMessage]) -> usize {
        // A show's tree holds the clips on screen: a clip change is a namespace change.
        let shown = shown_clips(instance);
        if shown != self.shown {
            self.shown = shown;
            self.path_changed = true;
        }
        let mut changes = std::borrow::Cow::Borrowed(changes);
        let bpm = instance.tempo.bpm;
        if self.bpm.is_none_or(|last| (last - bpm).abs() > 1e-3) {
            self.bpm = Some(bpm);
            let args = vec![rosc::OscType::Float(bpm as f32)];
            changes.to_mut().push(OscMessage { addr: "/indra/tempo/bpm".into(), args });
        }
        if publish || self.path_changed {
            self.publish(instance);
        }
        if std::mem::take(&mut self.path_changed) {
            self.listeners.path_changed("/indra");
        }
        if changes.is_empty() { 0 } else { self.listeners.send(&changes) }
    }

    /// The preset names the tree offers; a change is published and announced after the next
    /// frame.
    pub fn set_presets(&mut self, names: &[String]) {
        if names != self.presets {
            self.presets = names.to_vec();
            self.path_changed = true;
        }
    }

    /// A new scene: the namespace change is announced after the next frame, once the new tree is
    /// published.
    pub fn scene_changed(&mut self) {
        self.path_changed = true;
    }

    /// Changes not delivered because a controller's queue was full.
    pub fn dropped(&self) -> u64 {
        self.listeners.dropped()
    }
}

impl Drop for OscQueryServer {
    fn drop(&mut self) {
        self.listeners.close();
    }
}
