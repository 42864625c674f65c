//! A hostile-network soak for installations: floods the real OSC receiver over loopback UDP with
//! a mix of random bytes, corrupted packets, distinct unknown addresses with long names, bad
//! arguments, deeply nested bundles and far-future time tags, while a render-loop stand-in drains
//! and routes 60 times a second. Prints resident memory before and after, and the bytes logged.
//!
//! `cargo run --release --example osc_flood -- 1000000 2> flood.log; wc -c flood.log`

use std::net::UdpSocket;
use std::time::{Duration, Instant, SystemTime};

use indra::assets::Assets;
use indra::control::osc::OscReceiver;
use indra::control::osc_route::OscRouter;
use indra::geometry::SplitMix64;
use indra::scene::load_scene;
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

fn resident_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmRSS:")).and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

fn encode(packet: OscPacket) -> Vec<u8> {
    rosc::encoder::encode(&packet).expect("encodable")
}

/// Packet `i` of the flood.
fn hostile(i: u64, rng: &mut SplitMix64) -> Vec<u8> {
    let message = |addr: String, args| OscPacket::Message(OscMessage { addr, args });
    match i % 6 {
        0 => (0..rng.below(200)).map(|_| rng.next_u64() as u8).collect(),
        1 => encode(message(format!("/indra/nowhere/{}/{}", i, "x".repeat(200)), vec![OscType::Int(1)])),
        2 => encode(message("/indra/limit_set/scale".into(), vec![OscType::String("y".repeat(300))])),
        3 => {
            let inner = encode(message("/indra/limit_set/scale".into(), vec![OscType::Float(2.0)]));
            let mut packet = inner;
            for _ in 0..40 {
                let mut outer = b"#bundle\0\0\0\0\0\0\0\0\x01".to_vec();
                outer.extend_from_slice(&(packet.len() as u32).to_be_bytes());
                outer.extend_from_slice(&packet);
                packet = outer;
            }
            packet
        }
        4 => encode(OscPacket::Bundle(OscBundle {
            timetag: OscTime::try_from(SystemTime::now() + Duration::from_secs(30 + i % 1000)).expect("in range"),
            content: vec![message("/indra/limit_set/scale".into(), vec![OscType::Float(1.5)])],
        })),
        _ => encode(message("/indra/limit_set/scale".into(), vec![OscType::Float(f32::NAN)])),
    }
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let count: u64 = std::env::args().nth(1).and_then(|n| n.parse().ok()).unwrap_or(1_000_000);
    let scene = load_scene(&Assets::new(Some(env!("CARGO_MANIFEST_DIR").into())), "kleinian").expect("scene");
    let mut rx = OscReceiver::bind("127.0.0.1:0").expect("bind");
    let router = OscRouter::new(&scene);
    let target = rx.local_addr();
    let before = resident_kib();
    let sender = std::thread::spawn(move || {
        let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
        let mut rng = SplitMix64::new(0x2545_F491_4F6C_DD1D);
        for i in 0..count {
            let _ = socket.send_to(&hostile(i, &mut rng), target);
        }
    });
    let started = Instant::now();
    let mut routed = 0u64;
    while !sender.is_finished() || started.elapsed() < Duration::from_secs(1) {
        for batch in rx.drain(SystemTime::now()) {
            routed += batch.messages.iter().filter(|m| router.route(m, &scene, &rx).is_some()).count() as u64;
        }
        std::thread::sleep(Duration::from_millis(16));
    }
    let after = resident_kib();
    let [packets, messages, malformed, unknown, bad, applied, dropped] = rx.counters().snapshot();
    println!("sent {count} packets in {:.1} s", started.elapsed().as_secs_f64());
    println!(
        "received {packets}, messages {messages}, malformed {malformed}, unknown address {unknown}, bad arguments {bad}, applied {applied}, dropped {dropped}, routed {routed}"
    );
    println!("resident memory {before} KiB → {after} KiB ({:+} KiB)", after as i64 - before as i64);
}
