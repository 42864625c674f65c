//! Lights: DMX512 over Art-Net 4 and sACN (E1.31). A patch file places LED fixtures on one of
//! the show's images; the GPU averages each LED's box of it ([`PixelMap`]), the [`Layout`]
//! encodes the values into universes, and [`DmxOut`] sends them from a thread of its own at
//! the patch's rate. [`DmxIn`] receives universes from a lighting desk for the control layer.

mod artnet;
mod layout;
mod live;
mod ofl;
mod patch;
mod pixel_map;
mod receive;
mod sacn_out;
mod sender;

pub use artnet::{ARTNET_PORT, ArtNetSender};
pub use layout::{Layout, PixelBox, PixelSlot, UNIVERSE_CHANNELS, Universes};
pub use live::LiveLights;
pub use ofl::{LampMode, Slot};
pub use patch::{ArtNetOut, Fixture, Lamp, MatrixOrder, OnStop, Patch, PixelFormat, SacnOut, Shape, ron_options};
pub use pixel_map::PixelMap;
pub use receive::{DmxIn, DmxInCounts, ListenConfig, Merge};
pub use sacn_out::{SACN_PORT, SacnSender};
pub use sender::{DmxOut, REFRESH};

use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};

/// "IP" or "IP:PORT" (or a host name) as a socket address, `port` when none is given.
fn socket_address(text: &str, port: u16) -> Result<SocketAddr, String> {
    let with_port = if text.parse::<std::net::IpAddr>().is_ok() { format!("{text}:{port}") } else { text.to_string() };
    let with_port = if with_port.contains(':') { with_port } else { format!("{with_port}:{port}") };
    with_port
        .to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .ok_or_else(|| format!("'{text}' is not an address (IP or IP:PORT)"))
}

/// Each of `texts` as a socket address ([`socket_address`]).
fn socket_addresses(texts: &[String], port: u16) -> Result<Vec<SocketAddr>, String> {
    texts.iter().map(|t| socket_address(t, port)).collect()
}

/// A UDP socket bound to `at` that shares its port with other programs on the machine (a desk
/// tool or OLA listening on the same port at another address).
fn bind_udp(at: SocketAddr) -> std::io::Result<UdpSocket> {
    use socket2::{Domain, Protocol, Socket, Type};
    let socket = Socket::new(Domain::for_address(at), Type::DGRAM, Some(Protocol::UDP))?;
    socket.set_reuse_address(true)?;
    socket.bind(&at.into())?;
    Ok(socket.into())
}
