//! Which sites may talk to the control server. A browser sends every page's requests with the
//! `Host` the page's URL named and, for a WebSocket, the page's `Origin`; both are checked here:
//! - **Host** (DNS rebinding): a page of `evil.example` whose name an attacker then points at
//!   127.0.0.1 reaches the server as `Host: evil.example:PORT`. Only the names the server is
//!   bound as are answered — its address, `localhost`, the machine's own names and addresses,
//!   and what the performer adds (`--web-host`); others get `421`. A request without `Host`
//!   (no browser sends one) is taken, as OSCQuery clients may omit it.
//! - **Origin** (cross-site WebSockets): browsers let any page open a WebSocket anywhere, with
//!   the performer's cookie when the sites share a host (ports do not separate sites for
//!   cookies). An upgrade whose `Origin` is neither the server's own nor one the performer
//!   allowed (`--oscquery-cors`) is refused with `403`; an allowed one controls the show only
//!   with the token, like any client. Clients that are not browsers send no `Origin`.

use std::collections::BTreeSet;
use std::net::SocketAddr;

/// What the performer opened beyond the server's own names.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SiteRules {
    /// More names the server answers as (`--web-host`: a DNS name of the venue's network).
    pub hosts: Vec<String>,
    /// Origins of third-party OSCQuery web clients allowed to read the tree and open a
    /// WebSocket (`--oscquery-cors http://host:port`).
    pub cors: Vec<String>,
}

/// Where a request's page comes from, as its `Origin` says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// No `Origin` header: not a browser page (a controller, a script, `oscsend`).
    Absent,
    /// A page this server served.
    Own,
    /// A third-party client the performer allowed.
    Allowed,
    /// Any other site.
    Foreign,
}

/// The names and origins a running server accepts.
#[derive(Clone, Debug)]
pub struct SiteGuard {
    port: u16,
    /// Host names and addresses, lowercase, IPv6 without brackets.
    hosts: BTreeSet<String>,
    /// Allowed origins, lowercase, without a trailing slash.
    cors: Vec<String>,
}

impl SiteGuard {
    /// The guard of a server bound to `local`: its address (every address of the machine when
    /// it listens on all), `localhost` and loopback, the machine's name (and `NAME.local`, as
    /// mDNS announces it), and `rules`' hosts.
    pub fn new(local: SocketAddr, rules: &SiteRules) -> Self {
        let mut hosts: BTreeSet<String> = ["localhost", "127.0.0.1", "::1"].into_iter().map(String::from).collect();
        hosts.insert(local.ip().to_string());
        if local.ip().is_unspecified() {
            let all = if_addrs::get_if_addrs().unwrap_or_default();
            hosts.extend(all.into_iter().map(|interface| interface.ip().to_string()));
        }
        let name = gethostname::gethostname().to_string_lossy().to_ascii_lowercase();
        if !name.is_empty() {
            hosts.insert(format!("{name}.local"));
            hosts.insert(name);
        }
        hosts.extend(rules.hosts.iter().map(|h| bare_host(h).to_ascii_lowercase()));
        let cors = rules.cors.iter().map(|o| o.trim_end_matches('/').to_ascii_lowercase()).collect();
        Self { port: local.port(), hosts, cors }
    }

    /// Whether a request's `Host` header names this server (or the request has none).
    pub fn host_ok(&self, host: Option<&str>) -> bool {
        let Some(host) = host else { return true };
        let (name, port) = split_port(host);
        port.is_none_or(|p| p == self.port) && self.hosts.contains(&name.to_ascii_lowercase())
    }

    /// Where a request's page comes from, by its `Origin` header.
    pub fn origin(&self, origin: Option<&str>) -> Origin {
        let Some(origin) = origin else { return Origin::Absent };
        let origin = origin.trim_end_matches('/').to_ascii_lowercase();
        if self.cors.contains(&origin) {
            return Origin::Allowed;
        }
        let own = origin.strip_prefix("http://").or_else(|| origin.strip_prefix("https://")).is_some_and(|site| {
            let (name, port) = split_port(site);
            // A page served here names this port; a default port would be another server.
            port == Some(self.port) && self.hosts.contains(name)
        });
        if own { Origin::Own } else { Origin::Foreign }
    }

    /// The CORS headers for a reply to a request whose `Origin` header is `header`, from a page
    /// of `origin` (as [`SiteGuard::origin`] classed it): an allowed third-party origin may read it.
    pub fn cors_headers(header: Option<&str>, origin: Origin) -> Vec<(&'static str, String)> {
        match (origin, header) {
            (Origin::Allowed, Some(origin)) => {
                vec![("Access-Control-Allow-Origin", origin.to_string()), ("Vary", "Origin".to_string())]
            }
            _ => Vec::new(),
        }
    }
}

/// `host[:port]` or `[v6][:port]` split into the bare host and its port, if any.
fn split_port(site: &str) -> (&str, Option<u16>) {
    if let Some(rest) = site.strip_prefix('[') {
        let (v6, after) = rest.split_once(']').unwrap_or((rest, ""));
        return (v6, after.strip_prefix(':').and_then(|p| p.parse().ok()));
    }
    match site.rsplit_once(':') {
        // One colon: a port. More: an IPv6 address without brackets (no port).
        Some((name, port)) if !name.contains(':') => (name, Some(port.parse().unwrap_or(0))),
        _ => (site, None),
    }
}

/// A host as the performer may write it (`name`, `name:port`, `[v6]`), bare.
fn bare_host(host: &str) -> &str {
    let (name, _) = split_port(host.trim());
    name
}

#[cfg(test)]
mod tests {
    use super::super::http::Request;
    use super::*;

    fn guard(local: &str, rules: SiteRules) -> SiteGuard {
        SiteGuard::new(local.parse().unwrap(), &rules)
    }

    fn with(headers: &str) -> Request<'_> {
        Request::new("/", headers)
    }

    #[test]
    fn only_the_names_the_server_is_bound_as_are_answered() {
        let g = guard("127.0.0.1:8080", SiteRules { hosts: vec!["stage.example".into()], cors: Vec::new() });
        for ok in ["127.0.0.1:8080", "localhost:8080", "LOCALHOST", "[::1]:8080", "stage.example:8080", ""] {
            let headers = if ok.is_empty() { String::new() } else { format!("Host: {ok}") };
            assert!(g.host_ok(with(&headers).header("host")), "{ok}");
        }
        for bad in ["evil.example:8080", "evil.example", "127.0.0.1:9999", "127.0.0.1.evil.example:8080"] {
            assert!(!g.host_ok(with(&format!("Host: {bad}")).header("host")), "{bad}");
        }
        let name = gethostname::gethostname().to_string_lossy().to_string();
        assert!(g.host_ok(with(&format!("Host: {name}:8080")).header("host")), "the machine's own name");
        assert!(g.host_ok(with(&format!("Host: {name}.local:8080")).header("host")), "its mDNS name");
    }

    #[test]
    fn a_page_of_this_server_is_own_others_are_foreign_unless_allowed() {
        let rules = SiteRules { hosts: Vec::new(), cors: vec!["http://127.0.0.1:5173/".into()] };
        let g = guard("127.0.0.1:8080", rules);
        let origin = |o: &str| g.origin(with(&format!("Origin: {o}")).header("origin"));
        assert_eq!(g.origin(with("").header("origin")), Origin::Absent);
        assert_eq!(origin("http://127.0.0.1:8080"), Origin::Own);
        assert_eq!(origin("http://localhost:8080"), Origin::Own);
        assert_eq!(origin("http://127.0.0.1:5173"), Origin::Allowed);
        for foreign in ["http://127.0.0.1:8081", "http://evil.example", "http://127.0.0.1", "null", "file://"] {
            assert_eq!(origin(foreign), Origin::Foreign, "{foreign}");
        }
        let cors = |o: &str| {
            let request = format!("Origin: {o}");
            SiteGuard::cors_headers(with(&request).header("origin"), g.origin(with(&request).header("origin")))
        };
        assert_eq!(
            cors("http://127.0.0.1:5173")[0],
            ("Access-Control-Allow-Origin", "http://127.0.0.1:5173".to_string())
        );
        assert!(cors("http://evil.example").is_empty());
    }
}
