//! Art-Net 4 out: ArtDmx to the nodes named, ArtSync after each frame, and ArtPollReply to
//! desks and nodes that poll the address indra is bound to. Packets are built and parsed by
//! the `artnet_protocol` crate, except ArtSync, which it leaves unimplemented (it writes no
//! protocol version): that one is 14 fixed bytes, written here.

use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use artnet_protocol::{ArtCommand, Output, PollReply};

use super::patch::ArtNetOut;

/// Art-Net's UDP port.
pub const ARTNET_PORT: u16 = 6454;
/// ArtPolls answered in one second at most: a reply is larger than a poll, so a flood of
/// (spoofed) polls must not turn indra into an amplifier. Desks poll every few seconds.
const MAX_REPLIES_PER_SECOND: u32 = 20;

/// Sends one patch's universes over Art-Net.
pub struct ArtNetSender {
    socket: UdpSocket,
    targets: Vec<SocketAddr>,
    sync: bool,
    sequence: u8,
    poll: Option<PollResponder>,
}

impl ArtNetSender {
    /// Opens the socket (bound where the patch says, else any address) and, when bound, the
    /// thread that answers ArtPoll for `universes`.
    pub fn open(config: &ArtNetOut, universes: &[u16]) -> Result<Self, String> {
        let targets = super::socket_addresses(&config.to, ARTNET_PORT).map_err(|e| format!("artnet.to: {e}"))?;
        let (socket, poll) = match &config.bind {
            Some(bind) => {
                let at = super::socket_address(bind, ARTNET_PORT).map_err(|e| format!("artnet.bind: {e}"))?;
                let socket = super::bind_udp(at).map_err(|e| format!("cannot bind Art-Net to {at}: {e}"))?;
                let poll = PollResponder::start(&socket, at, universes)?;
                (socket, Some(poll))
            }
            None => (UdpSocket::bind("0.0.0.0:0").map_err(|e| format!("cannot open an Art-Net socket: {e}"))?, None),
        };
        socket.set_broadcast(true).ok();
        Ok(Self { socket, targets, sync: config.sync, sequence: 0, poll })
    }

    /// Sends one universe (ArtDmx) to every node.
    pub fn send(&mut self, universe: u16, channels: &[u8]) {
        // Sequence 1–255 (0 would switch re-ordering off at the node).
        self.sequence = self.sequence % 255 + 1;
        let Ok(port_address) = universe.try_into() else { return };
        let packet = ArtCommand::Output(Output {
            sequence: self.sequence,
            port_address,
            data: channels.to_vec().into(),
            ..Output::default()
        });
        if let Ok(bytes) = packet.write_to_buffer() {
            for target in &self.targets {
                let _ = self.socket.send_to(&bytes, target);
            }
        }
    }

    /// Ends a frame: ArtSync, when the patch asks for it.
    pub fn end_frame(&mut self) {
        if !self.sync {
            return;
        }
        let mut bytes = [0u8; 14];
        bytes[..8].copy_from_slice(b"Art-Net\0");
        bytes[8..10].copy_from_slice(&0x5200u16.to_le_bytes());
        bytes[10..12].copy_from_slice(&[0, 14]);
        for target in &self.targets {
            let _ = self.socket.send_to(&bytes, target);
        }
    }

    /// Polls answered so far.
    pub fn polls_answered(&self) -> u64 {
        self.poll.as_ref().map_or(0, |p| p.answered.load(Ordering::Relaxed))
    }
}

/// A thread answering ArtPoll on the bound socket.
struct PollResponder {
    stop: Arc<AtomicBool>,
    answered: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

impl PollResponder {
    fn start(socket: &UdpSocket, at: SocketAddr, universes: &[u16]) -> Result<Self, String> {
        let socket = socket.try_clone().map_err(|e| e.to_string())?;
        socket.set_read_timeout(Some(Duration::from_millis(200))).map_err(|e| e.to_string())?;
        let reply = poll_reply(at, universes);
        let stop = Arc::new(AtomicBool::new(false));
        let answered = Arc::new(AtomicU64::new(0));
        let (stopping, counting) = (stop.clone(), answered.clone());
        let thread = std::thread::Builder::new()
            .name("artnet-poll".into())
            .spawn(move || {
                let mut buffer = [0u8; 1024];
                let (mut second, mut replies) = (std::time::Instant::now(), 0u32);
                while !stopping.load(Ordering::Relaxed) {
                    let Ok((n, from)) = socket.recv_from(&mut buffer) else { continue };
                    if second.elapsed() >= Duration::from_secs(1) {
                        (second, replies) = (std::time::Instant::now(), 0);
                    }
                    // Anything but a well-formed ArtPoll is ignored, and polls past the rate.
                    if replies >= MAX_REPLIES_PER_SECOND {
                        continue;
                    }
                    if let Ok(ArtCommand::Poll(_)) = ArtCommand::from_buffer(&buffer[..n]) {
                        replies += 1;
                        let to = SocketAddr::new(from.ip(), ARTNET_PORT);
                        let _ = socket.send_to(&reply, to);
                        if to != from {
                            let _ = socket.send_to(&reply, from);
                        }
                        counting.fetch_add(1, Ordering::Relaxed);
                    }
                }
            })
            .map_err(|e| e.to_string())?;
        Ok(Self { stop, answered, thread: Some(thread) })
    }
}

impl Drop for PollResponder {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// indra's ArtPollReply: a controller (output) node with up to four of its universes.
fn poll_reply(at: SocketAddr, universes: &[u16]) -> Vec<u8> {
    let mut reply = PollReply::default();
    if let std::net::IpAddr::V4(ip) = at.ip() {
        reply.address = ip;
        reply.bind_ip = ip.octets();
    }
    reply.port = ARTNET_PORT;
    reply.version = [0, 1];
    let first = universes.first().copied().unwrap_or(0);
    reply.port_address = [((first >> 8) & 0x7f) as u8, ((first >> 4) & 0x0f) as u8];
    let copy = |to: &mut [u8], text: &str| {
        let n = text.len().min(to.len() - 1);
        to[..n].copy_from_slice(&text.as_bytes()[..n]);
    };
    copy(&mut reply.short_name, "indra");
    copy(&mut reply.long_name, "indra visuals: pixel map out");
    copy(&mut reply.node_report, "#0001 [0000] indra sending");
    let ports = universes.iter().filter(|u| (*u >> 4) == (first >> 4)).take(4).collect::<Vec<_>>();
    reply.num_ports = [0, ports.len() as u8];
    for (i, u) in ports.iter().enumerate() {
        // DMX512 ports that take data from the network into... the network: indra is an input
        // to Art-Net (bit 6), sending on these universes.
        reply.port_types[i] = 0x40;
        reply.good_input[i] = 0x80;
        reply.swin[i] = (**u & 0x0f) as u8;
    }
    reply.style = 0x01; // StController
    ArtCommand::PollReply(Box::new(reply)).write_to_buffer().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn artsync_is_the_fourteen_bytes_of_the_standard_and_artdmx_parses_back() {
        let receiver = UdpSocket::bind("127.0.0.1:0").unwrap();
        receiver.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let config = ArtNetOut { to: vec![receiver.local_addr().unwrap().to_string()], bind: None, sync: true };
        let mut sender = ArtNetSender::open(&config, &[5]).unwrap();
        let mut channels = [0u8; 512];
        channels[0] = 7;
        channels[511] = 9;
        sender.send(5, &channels);
        sender.end_frame();
        let mut buffer = [0u8; 1024];
        let n = receiver.recv(&mut buffer).unwrap();
        match ArtCommand::from_buffer(&buffer[..n]).unwrap() {
            ArtCommand::Output(o) => {
                assert_eq!(u16::from(o.port_address), 5);
                assert_eq!(o.sequence, 1);
                assert_eq!(o.data.as_ref().as_slice(), &channels);
            }
            other => panic!("not ArtDmx: {other:?}"),
        }
        let n = receiver.recv(&mut buffer).unwrap();
        assert_eq!(&buffer[..n], b"Art-Net\0\x00\x52\x00\x0e\x00\x00");
    }

    #[test]
    fn a_bound_sender_answers_artpoll_with_its_name() {
        let bind = "127.0.0.3:6454".to_string();
        let config = ArtNetOut { to: vec!["127.0.0.1:9".into()], bind: Some(bind), sync: false };
        let sender = ArtNetSender::open(&config, &[1, 2]).unwrap();
        let desk = super::super::bind_udp("127.0.0.4:6454".parse().unwrap()).unwrap();
        desk.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let poll = ArtCommand::Poll(Default::default()).write_to_buffer().unwrap();
        desk.send_to(&poll, "127.0.0.3:6454").unwrap();
        let mut buffer = [0u8; 1024];
        let n = desk.recv(&mut buffer).unwrap();
        match ArtCommand::from_buffer(&buffer[..n]).unwrap() {
            ArtCommand::PollReply(reply) => {
                assert!(reply.short_name.starts_with(b"indra"));
                assert_eq!(reply.num_ports, [0, 2]);
                assert_eq!(reply.address, std::net::Ipv4Addr::new(127, 0, 0, 3));
            }
            other => panic!("not ArtPollReply: {other:?}"),
        }
        // The responder counts after it has sent.
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        while sender.polls_answered() == 0 && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        assert_eq!(sender.polls_answered(), 1);
    }

    #[test]
    fn a_flood_of_polls_gets_twenty_replies_a_second_at_most() {
        let config = ArtNetOut { to: vec!["127.0.0.1:9".into()], bind: Some("127.0.0.5:6454".into()), sync: false };
        let sender = ArtNetSender::open(&config, &[1]).unwrap();
        let desk = super::super::bind_udp("127.0.0.6:6454".parse().unwrap()).unwrap();
        desk.set_read_timeout(Some(Duration::from_millis(300))).unwrap();
        let poll = ArtCommand::Poll(Default::default()).write_to_buffer().unwrap();
        for _ in 0..200 {
            desk.send_to(&poll, "127.0.0.5:6454").unwrap();
        }
        let mut buffer = [0u8; 1024];
        let mut replies = 0;
        while desk.recv(&mut buffer).is_ok() {
            replies += 1;
        }
        // The burst may straddle the start of a second: two seconds' worth at the most.
        assert!((1..=2 * MAX_REPLIES_PER_SECOND).contains(&replies), "{replies} replies to 200 polls");
        assert!(sender.polls_answered() <= u64::from(2 * MAX_REPLIES_PER_SECOND));
    }
}
