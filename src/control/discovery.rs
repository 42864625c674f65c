//! DNS-SD over multicast DNS (`mdns-sd`): the OSCQuery server is advertised as `_oscjson._tcp`
//! and the OSC input as `_osc._udp`, so controllers on the venue network find indra without
//! typing an address. A network without multicast is a logged fact; the servers still run.

use std::net::SocketAddr;

use mdns_sd::{ServiceDaemon, ServiceInfo};

/// The OSCQuery service type.
pub const OSCQUERY_SERVICE: &str = "_oscjson._tcp.local.";
/// The OSC service type.
pub const OSC_SERVICE: &str = "_osc._udp.local.";

/// Services advertised while this lives.
pub struct Advertisement {
    daemon: ServiceDaemon,
    names: Vec<String>,
}

impl Advertisement {
    /// Advertises the OSCQuery server at `http` and, when `osc_port` is not 0, the OSC input, as
    /// instance `name`. A server bound to one address is advertised at that address, one bound
    /// to all at every interface's; a loopback-only server is not advertised (nobody else could
    /// reach it).
    pub fn start(name: &str, http: SocketAddr, osc_port: u16) -> Result<Self, String> {
        if http.ip().is_loopback() {
            return Err(format!("OSCQuery on {http} is loopback only: not advertised on the network"));
        }
        let daemon = ServiceDaemon::new().map_err(|e| format!("cannot start mDNS: {e}"))?;
        let host = format!("{}.local.", host_name());
        // Bound to all addresses: every interface's, found by mdns-sd; else the one bound.
        let every = http.ip().is_unspecified();
        let ip = if every { String::new() } else { http.ip().to_string() };
        let mut names = Vec::new();
        let mut services = vec![(OSCQUERY_SERVICE, http.port())];
        if osc_port != 0 {
            services.push((OSC_SERVICE, osc_port));
        }
        for (service, port) in services {
            let info = ServiceInfo::new(
                service,
                name,
                &host,
                ip.as_str(),
                port,
                None::<std::collections::HashMap<String, String>>,
            )
            .map_err(|e| format!("cannot describe {service} for mDNS: {e}"))?;
            let info = if every { info.enable_addr_auto() } else { info };
            names.push(info.get_fullname().to_string());
            daemon.register(info).map_err(|e| format!("cannot advertise {service} over mDNS: {e}"))?;
        }
        log::info!("advertised over mDNS as \"{name}\" ({})", names.join(", "));
        Ok(Self { daemon, names })
    }
}

impl Drop for Advertisement {
    fn drop(&mut self) {
        for name in &self.names {
            let _ = self.daemon.unregister(name);
        }
        let _ = self.daemon.shutdown();
    }
}

/// This machine's host name as a DNS label (letters, digits and hyphens), or `indra`.
fn host_name() -> String {
    // Windows names the machine in COMPUTERNAME; Linux shells export HOSTNAME, services may not.
    let raw = std::env::var("HOSTNAME")
        .or_else(|_| std::env::var("COMPUTERNAME"))
        .ok()
        .or_else(|| std::fs::read_to_string("/proc/sys/kernel/hostname").ok())
        .or_else(|| std::fs::read_to_string("/etc/hostname").ok())
        .unwrap_or_default();
    let label: String = raw.trim().chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect();
    let label = label.trim_matches('-');
    if label.is_empty() { "indra".into() } else { label.chars().take(63).collect() }
}
