//! OSCQuery: an HTTP endpoint serving the JSON address tree (FULL_PATH, CONTENTS, TYPE, RANGE,
//! VALUE, ACCESS, DESCRIPTION, per the OSCQuery proposal by Vidvox) and HOST_INFO, so
//! TouchOSC-style clients discover every parameter. The render loop publishes snapshots; the
//! server thread only reads them.

use std::sync::{Arc, RwLock};

use serde_json::{Map, Value, json};

use super::address::param_address;
use super::http::HttpServer;
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

/// The OSCQuery endpoint: the published tree, served over HTTP.
pub struct OscQueryServer {
    snapshot: Arc<RwLock<Value>>,
    server: HttpServer,
}

impl OscQueryServer {
    /// Serves on `addr` (port 0 picks one), advertising `osc_port` in HOST_INFO. The server has
    /// hard limits (see [`super::http`]): no request can exhaust memory or hold up the others.
    pub fn start(addr: &str, osc_port: u16) -> Result<Self, String> {
        let snapshot = Arc::new(RwLock::new(json!({ "FULL_PATH": "/", "CONTENTS": {} })));
        let tree = snapshot.clone();
        let handler = Arc::new(move |target: &str| {
            let (path, query) = target.split_once('?').unwrap_or((target, ""));
            let body = if query.contains("HOST_INFO") {
                Some(host_info(osc_port))
            } else {
                tree.read().ok().and_then(|t| subtree(&t, path).cloned())
            };
            match body {
                Some(v) => (200, v.to_string()),
                None => (404, "{}".to_string()),
            }
        });
        let server = HttpServer::start(addr, "oscquery", handler)?;
        log::info!("OSCQuery on http://{}/", server.local_addr());
        Ok(Self { snapshot, server })
    }

    /// The bound address.
    pub fn local_addr(&self) -> std::net::SocketAddr {
        self.server.local_addr()
    }

    /// Publishes the current tree.
    pub fn publish(&self, instance: &SceneInstance) {
        let t = tree(instance);
        if let Ok(mut s) = self.snapshot.write() {
            *s = t;
        }
    }
}
