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
use super::http::{HttpServer, Routes};
use super::listen::Listeners;
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

/// The whole address tree of `instance` with current values.
pub fn tree(instance: SceneView<'_>) -> Value {
    let mut nodes = Map::new();
    for (n, node) in instance.scene.nodes.iter().enumerate() {
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
            leaf.insert("DESCRIPTION".into(), json!(decl.doc));
            contents.insert(decl.name.clone(), Value::Object(leaf));
        }
        let path = format!("/indra/{}", node.id);
        nodes.insert(
            node.id.clone(),
            json!({ "FULL_PATH": path, "CONTENTS": contents, "DESCRIPTION": node.technique.summary }),
        );
    }
    json!({
        "FULL_PATH": "/",
        "CONTENTS": { "indra": { "FULL_PATH": "/indra", "CONTENTS": nodes, "DESCRIPTION": instance.scene.name } }
    })
}

/// The HOST_INFO reply.
pub fn host_info(osc_port: u16) -> Value {
    json!({
        "NAME": "indra",
        "OSC_PORT": osc_port,
        "OSC_TRANSPORT": "UDP",
        "EXTENSIONS": {
            "ACCESS": true, "VALUE": true, "RANGE": true, "DESCRIPTION": true, "TYPE": true,
            "LISTEN": true, "PATH_CHANGED": true
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
    server: HttpServer,
    /// Kept for its lifetime: dropping it withdraws the advertisement.
    _advertisement: Option<Advertisement>,
}

impl OscQueryServer {
    /// Serves on `addr` (port 0 picks one), naming `osc_port` in HOST_INFO and advertising both
    /// over mDNS unless `addr` is loopback. The server has hard limits (see [`super::http`]):
    /// no request can exhaust memory or hold up the others. mDNS that cannot start is logged.
    pub fn start(addr: &str, osc_port: u16) -> Result<Self, String> {
        let snapshot: Arc<RwLock<Option<Value>>> = Arc::default();
        let tree = snapshot.clone();
        let handler = Arc::new(move |target: &str| {
            let (path, query) = target.split_once('?').unwrap_or((target, ""));
            if query.contains("HOST_INFO") {
                return (200, host_info(osc_port).to_string());
            }
            let Ok(tree) = tree.read() else { return (503, "{}".to_string()) };
            // Until the show has built its scene there is no tree: a controller connecting at
            // start-up is told to come back, not shown an empty show.
            match tree.as_ref().map(|t| subtree(t, path)) {
                None => (503, "{}".to_string()),
                Some(Some(v)) => (200, v.to_string()),
                Some(None) => (404, "{}".to_string()),
            }
        });
        let listeners = Arc::new(Listeners::default());
        let sessions = listeners.clone();
        let routes = Routes { get: handler, socket: Some(Arc::new(move |socket| sessions.serve(socket))) };
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
        Ok(Self { snapshot, listeners, path_changed: false, server, _advertisement: advertisement })
    }

    /// The bound address.
    pub fn local_addr(&self) -> std::net::SocketAddr {
        self.server.local_addr()
    }

    /// Publishes the current tree.
    pub fn publish(&self, instance: SceneView<'_>) {
        let t = tree(instance);
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
        if publish || self.path_changed {
            self.publish(instance);
        }
        if std::mem::take(&mut self.path_changed) {
            self.listeners.path_changed("/indra");
        }
        if changes.is_empty() { 0 } else { self.listeners.send(changes) }
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
