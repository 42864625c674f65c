//! The control surface in the browser: a page served by the OSCQuery server that builds its
//! controls from the address tree, follows values through LISTEN and writes them as binary OSC
//! over the same WebSocket — which the server takes through the very inlet, limits and counters
//! of UDP OSC ([`super::osc::OscInlet`]), so a browser's writes are ordinary control events,
//! recorded and replayed like any other.
//!
//! Access: the server listens on loopback unless told otherwise; the page, and control over the
//! WebSocket, need the [`AccessToken`] the URL carries. Without it a client may still read the
//! tree and LISTEN (what any OSCQuery client may), but a session that sends OSC is closed.

pub mod access;
pub mod qr;

use std::net::{IpAddr, SocketAddr};

pub use access::AccessToken;

use super::http::{Reply, Request};
use super::site::Origin;

/// Where `--web` listens when given no address: loopback, so nothing on the network reaches it.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";

/// How the surface is served.
#[derive(Clone, Debug)]
pub struct WebOptions {
    /// Listen address (`host:port`); the OSCQuery tree is served here too.
    pub addr: String,
    /// Pages show the values but cannot change them (a display in the foyer).
    pub read_only: bool,
    /// The secret that grants control.
    pub token: AccessToken,
    /// WebSocket sessions open at once (pages and OSCQuery clients together), 1–256.
    pub sessions: usize,
}

/// The range of [`WebOptions::sessions`].
pub const SESSIONS: std::ops::RangeInclusive<usize> = 1..=256;

const INDEX: &str = include_str!("page/index.html");
const APP_JS: &[u8] = include_bytes!("page/app.js");
const APP_CSS: &[u8] = include_bytes!("page/app.css");

/// What the page may load and where it may connect: its own files and its own server only.
const CONTENT_SECURITY: &str = "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; \
     connect-src 'self' ws: wss:; base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

impl WebOptions {
    /// The reply to a request the surface answers (the page and its files); `None` for the
    /// rest, which the OSCQuery tree answers.
    pub fn reply(&self, request: &Request<'_>) -> Option<Reply> {
        match request.path() {
            "/" if wants_page(request) => Some(self.page(request)),
            "/_web/app.js" => Some(with_guards(Reply::file("text/javascript; charset=utf-8", APP_JS))),
            "/_web/app.css" => Some(with_guards(Reply::file("text/css; charset=utf-8", APP_CSS))),
            _ => None,
        }
    }

    /// Whether a WebSocket session opened by `request` from a page of `origin` may control the
    /// show: with the token, which a third-party page must name in its URL (the performer's
    /// cookie speaks for this surface's own pages only).
    pub fn controls(&self, request: &Request<'_>, origin: Origin) -> bool {
        let token = match origin {
            Origin::Absent | Origin::Own => self.token.admits(request),
            Origin::Allowed => self.token.admits_in_url(request),
            Origin::Foreign => false,
        };
        !self.read_only && token
    }

    /// The page, for a request with the token; `401` and a line on how to get in without it.
    fn page(&self, request: &Request<'_>) -> Reply {
        if !self.token.admits(request) {
            let body = "<!doctype html><meta charset=utf-8><title>indra</title>\
                 <p>This control surface needs its access token: open the full URL indra printed \
                 when it started (or scan its QR code).</p>";
            return with_guards(html(401, body.into()));
        }
        let access = if self.read_only { "read-only" } else { "control" };
        let mut reply = with_guards(html(200, INDEX.replace("{{access}}", access)));
        // The cookie lets the page's WebSocket (and any OSCQuery page served from here) present
        // the token without it in every URL; Strict keeps other sites' pages from using it.
        let cookie = format!("{}={}; Path=/; HttpOnly; SameSite=Strict", access::COOKIE, self.token.as_str());
        reply.headers.push(("Set-Cookie", cookie));
        reply
    }
}

/// An HTML reply.
fn html(status: u16, body: String) -> Reply {
    Reply::text(status, "text/html; charset=utf-8", body)
}

/// A browser asking for a page (not a client asking for the root of the tree as JSON): HTML
/// accepted and no OSCQuery attribute asked for, only the token.
fn wants_page(request: &Request<'_>) -> bool {
    let html = request.header("accept").is_some_and(|a| a.contains("text/html"));
    let query = request.query();
    html && (query.is_empty() || query.split('&').all(|pair| pair.starts_with("token=")))
}

/// The headers every file of the page carries: no caching (the binary is the truth), no
/// sniffing, no referrer (the URL holds the token), its content policy.
fn with_guards(mut reply: Reply) -> Reply {
    reply.headers.extend([
        ("Cache-Control", "no-store".to_string()),
        ("X-Content-Type-Options", "nosniff".to_string()),
        ("Referrer-Policy", "no-referrer".to_string()),
        ("Content-Security-Policy", CONTENT_SECURITY.to_string()),
    ]);
    reply
}

/// The URLs a phone can open for a server bound to `local`: its own address, or each of the
/// machine's network addresses when it listens on all of them (`0.0.0.0`).
pub fn urls(local: SocketAddr, token: &AccessToken) -> Vec<String> {
    let url = |ip: IpAddr| match ip {
        IpAddr::V6(v6) => format!("http://[{v6}]:{}/?token={}", local.port(), token.as_str()),
        IpAddr::V4(v4) => format!("http://{v4}:{}/?token={}", local.port(), token.as_str()),
    };
    if !local.ip().is_unspecified() {
        return vec![url(local.ip())];
    }
    let mut found: Vec<IpAddr> = if_addrs::get_if_addrs()
        .unwrap_or_default()
        .into_iter()
        .map(|interface| interface.ip())
        .filter(|ip| !ip.is_loopback() && ip.is_ipv4() == local.is_ipv4())
        .collect();
    found.sort();
    found.dedup();
    if found.is_empty() {
        found.push(if local.is_ipv4() {
            IpAddr::from([127, 0, 0, 1])
        } else {
            IpAddr::from([0u16, 0, 0, 0, 0, 0, 0, 1])
        });
    }
    found.into_iter().map(url).collect()
}

/// The surface's URLs when served at `local` (each with the token), told to the performer: each
/// URL, and a QR code of the first for a phone's camera when the surface is on the network (not
/// on loopback).
pub fn announce(local: SocketAddr, web: &WebOptions) -> Vec<String> {
    let urls = urls(local, &web.token);
    let mode = if web.read_only { " (read-only)" } else { "" };
    for url in &urls {
        log::info!("control surface{mode} on {url}");
    }
    if let Some(first) = urls.first().filter(|_| !local.ip().is_loopback())
        && let Some(code) = qr::terminal(first)
    {
        log::info!("scan to open the control surface:\n{code}");
    }
    urls
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(read_only: bool) -> WebOptions {
        let token = AccessToken::chosen("test-token-0123").unwrap();
        WebOptions { addr: DEFAULT_ADDR.into(), read_only, token, sessions: 8 }
    }

    #[test]
    fn the_page_needs_the_token_and_json_clients_still_get_the_tree() {
        let web = options(false);
        let html = "Accept: text/html,application/xhtml+xml";
        let page = web.reply(&Request::new("/?token=test-token-0123", html)).unwrap();
        assert_eq!(page.status, 200);
        assert!(String::from_utf8_lossy(&page.body).contains(r#"content="control""#));
        assert!(page.headers.iter().any(|(n, v)| *n == "Set-Cookie" && v.contains("HttpOnly; SameSite=Strict")));
        assert_eq!(web.reply(&Request::new("/", html)).unwrap().status, 401);
        assert_eq!(web.reply(&Request::new("/?token=wrong-token-0123", html)).unwrap().status, 401);
        assert!(web.reply(&Request::new("/", "Accept: */*")).is_none(), "OSCQuery's root stays JSON");
        assert!(web.reply(&Request::new("/?HOST_INFO", html)).is_none());
        assert!(web.reply(&Request::new("/indra/glow", html)).is_none());
        assert_eq!(web.reply(&Request::new("/_web/app.js", "")).unwrap().status, 200);
        let read_only = options(true).reply(&Request::new("/?token=test-token-0123", html)).unwrap();
        assert!(String::from_utf8_lossy(&read_only.body).contains(r#"content="read-only""#));
    }

    #[test]
    fn control_needs_the_token_and_a_surface_that_is_not_read_only() {
        let with_cookie = Request::new("/", "Cookie: indra_token=test-token-0123");
        assert!(options(false).controls(&with_cookie, Origin::Own));
        assert!(options(false).controls(&with_cookie, Origin::Absent));
        assert!(!options(true).controls(&with_cookie, Origin::Own));
        assert!(!options(false).controls(&Request::new("/", ""), Origin::Own));
        // A third-party page carries the performer's cookie too: only a token it names counts.
        assert!(!options(false).controls(&with_cookie, Origin::Allowed));
        assert!(options(false).controls(&Request::new("/?token=test-token-0123", ""), Origin::Allowed));
        assert!(!options(false).controls(&Request::new("/?token=test-token-0123", ""), Origin::Foreign));
    }

    #[test]
    fn urls_name_the_bound_address_or_every_network_address() {
        let token = AccessToken::chosen("test-token-0123").unwrap();
        assert_eq!(urls("127.0.0.1:8080".parse().unwrap(), &token), ["http://127.0.0.1:8080/?token=test-token-0123"]);
        let all = urls("0.0.0.0:8080".parse().unwrap(), &token);
        assert!(!all.is_empty() && all.iter().all(|u| u.ends_with(":8080/?token=test-token-0123")), "{all:?}");
    }
}
