//! OSCQuery: an HTTP endpoint serving the JSON address tree (FULL_PATH, CONTENTS, TYPE, RANGE,
//! VALUE, ACCESS, DESCRIPTION, per the OSCQuery proposal by Vidvox) and HOST_INFO, so
//! TouchOSC-style clients discover every parameter. The render loop publishes snapshots; the
//! server thread only reads them.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, RwLock};
use std::thread::JoinHandle;
use std::time::Duration;

use serde_json::{Map, Value, json};

use super::address::param_address;
use crate::params::{ParamDecl, ParamType, ParamValue};
use crate::scene::SceneInstance;

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
pub fn tree(instance: &SceneInstance) -> Value {
    let mut nodes = Map::new();
    for (n, node) in instance.scene().nodes.iter().enumerate() {
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
        "CONTENTS": { "indra": { "FULL_PATH": "/indra", "CONTENTS": nodes, "DESCRIPTION": instance.scene().name } }
    })
}

/// The HOST_INFO reply.
pub fn host_info(osc_port: u16) -> Value {
    json!({
        "NAME": "indra",
        "OSC_PORT": osc_port,
        "OSC_TRANSPORT": "UDP",
        "EXTENSIONS": { "ACCESS": true, "VALUE": true, "RANGE": true, "DESCRIPTION": true, "TYPE": true }
    })
}

/// The node of `tree` at `path` (`/indra/limit_set/scale`), if it exists.
pub fn subtree<'a>(tree: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('/').filter(|s| !s.is_empty()).try_fold(tree, |node, part| node.get("CONTENTS")?.get(part))
}

/// The HTTP server thread.
pub struct OscQueryServer {
    snapshot: Arc<RwLock<Value>>,
    local: std::net::SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl OscQueryServer {
    /// Serves on `addr` (port 0 picks one), advertising `osc_port` in HOST_INFO.
    pub fn start(addr: &str, osc_port: u16) -> Result<Self, String> {
        let server = tiny_http::Server::http(addr).map_err(|e| format!("cannot serve OSCQuery on {addr}: {e}"))?;
        let local = server.server_addr().to_ip().ok_or("OSCQuery server has no IP address")?;
        let snapshot = Arc::new(RwLock::new(json!({ "FULL_PATH": "/", "CONTENTS": {} })));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (snapshot, stop) = (snapshot.clone(), stop.clone());
            std::thread::Builder::new()
                .name("indra-oscquery".into())
                .spawn(move || serve(&server, &snapshot, &stop, osc_port))
                .map_err(|e| e.to_string())?
        };
        log::info!("OSCQuery on http://{local}/");
        Ok(Self { snapshot, local, stop, thread: Some(thread) })
    }

    /// The bound address.
    pub fn local_addr(&self) -> std::net::SocketAddr {
        self.local
    }

    /// Publishes the current tree.
    pub fn publish(&self, instance: &SceneInstance) {
        let t = tree(instance);
        if let Ok(mut s) = self.snapshot.write() {
            *s = t;
        }
    }
}

impl Drop for OscQueryServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn serve(server: &tiny_http::Server, snapshot: &RwLock<Value>, stop: &AtomicBool, osc_port: u16) {
    while !stop.load(Ordering::Relaxed) {
        let Ok(Some(request)) = server.recv_timeout(Duration::from_millis(100)) else { continue };
        let url = request.url().to_string();
        let (path, query) = url.split_once('?').unwrap_or((&url, ""));
        let body = if query.contains("HOST_INFO") {
            Some(host_info(osc_port))
        } else {
            snapshot.read().ok().and_then(|t| subtree(&t, path).cloned())
        };
        let header = tiny_http::Header::from_bytes("Content-Type", "application/json").expect("valid header");
        let response = match body {
            Some(v) => tiny_http::Response::from_string(v.to_string()).with_header(header),
            None => tiny_http::Response::from_string("{}").with_status_code(404).with_header(header),
        };
        let _ = request.respond(response);
    }
}
