//! OSC over real UDP on loopback: messages of every argument type, clamping, atomic bundles,
//! future time tags, an external client (liblo's `oscsend`), 100,000 hostile packets, feedback
//! out, the OSCQuery tree, its LISTEN WebSocket and its mDNS advertisement.

use crate::common;

use std::net::UdpSocket;
use std::time::{Duration, Instant, SystemTime};

use indra::control::feedback::{OscFeedback, ParamChanges};
use indra::control::osc::{OscReceiver, decode};
use indra::control::osc_route::{OscRouter, Routed};
use indra::control::oscquery::OscQueryServer;
use indra::params::ParamValue;
use indra::scene::{ControlEvent, Scene, SceneInstance, SceneView, load_scene};
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

fn scene(name: &str) -> Scene {
    load_scene(&common::assets(), name).unwrap()
}

fn packet(addr: &str, args: Vec<OscType>) -> Vec<u8> {
    rosc::encoder::encode(&OscPacket::Message(OscMessage { addr: addr.into(), args })).unwrap()
}

/// Waits until the receiver has seen `n` packets, then drains every due batch.
fn receive(rx: &mut OscReceiver, n: u64) -> Vec<indra::control::osc::Batch> {
    let start = Instant::now();
    while rx.counters().packets.load(std::sync::atomic::Ordering::Relaxed) < n {
        assert!(start.elapsed() < Duration::from_secs(5), "only {:?} arrived", rx.counters().snapshot());
        std::thread::sleep(Duration::from_millis(2));
    }
    std::thread::sleep(Duration::from_millis(20));
    rx.drain(SystemTime::now())
}

/// Sends `packets`, routes what arrives, returns the events.
fn send_and_route(scene: &Scene, packets: &[Vec<u8>]) -> (Vec<Routed>, OscReceiver) {
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    for p in packets {
        tx.send_to(p, rx.local_addr()).unwrap();
    }
    let mut router = OscRouter::new(scene);
    let batches = receive(&mut rx, packets.len() as u64);
    router.begin_frame();
    let routed = batches.iter().flat_map(|b| &b.messages).flat_map(|m| router.route_all(m, scene, &rx)).collect();
    (routed, rx)
}

fn write_value(r: &Routed) -> ParamValue {
    match r {
        Routed::Event(ControlEvent::Write(w)) => w.value,
        other => panic!("not a write: {other:?}"),
    }
}

#[test]
fn every_argument_type_reaches_its_parameter() {
    let k = scene("kleinian");
    let (routed, rx) = send_and_route(
        &k,
        &[
            packet("/indra/limit_set/scale", vec![OscType::Float(2.5)]),
            packet("/indra/limit_set/scale", vec![OscType::Double(3.5)]),
            packet("/indra/limit_set/iterations", vec![OscType::Int(120)]),
            packet("/indra/limit_set/iterations", vec![OscType::Long(77)]),
            packet("/indra/limit_set/circle_inversion", vec![OscType::Bool(true)]),
            packet("/indra/limit_set/t", vec![OscType::Float(1.9), OscType::Float(0.03)]),
            packet("/indra/limit_set/hit_color", vec![OscType::Float(1.0), OscType::Float(0.5), OscType::Float(0.0)]),
            packet("/indra/limit_set/t/y", vec![OscType::Float(0.01)]),
        ],
    );
    let values: Vec<ParamValue> = routed.iter().map(write_value).collect();
    assert_eq!(
        values,
        [
            ParamValue::Float(2.5),
            ParamValue::Float(3.5),
            ParamValue::Int(120),
            ParamValue::Int(77),
            ParamValue::Bool(true),
            ParamValue::Vec2([1.9, 0.03]),
            ParamValue::Color([1.0, 0.5, 0.0, 1.0]),
            ParamValue::Float(0.01),
        ]
    );
    assert_eq!(rx.counters().snapshot()[5], 8, "all applied");
    // Enums by name or index (StarGlow's composite type).
    let s = scene("star_glow");
    let (routed, _) = send_and_route(
        &s,
        &[
            packet("/indra/glow/composite", vec![OscType::String("Screen".into())]),
            packet("/indra/glow/composite", vec![OscType::Int(4)]),
        ],
    );
    let values: Vec<ParamValue> = routed.iter().map(write_value).collect();
    assert_eq!(values, [ParamValue::Enum(1), ParamValue::Enum(4)]);
}

#[test]
fn wrong_arguments_and_unknown_addresses_are_counted_not_applied() {
    let k = scene("kleinian");
    let (routed, rx) = send_and_route(
        &k,
        &[
            packet("/indra/limit_set/t", vec![OscType::Float(1.0)]),
            packet("/indra/limit_set/scale", vec![OscType::String("big".into())]),
            packet("/indra/nowhere/x", vec![OscType::Float(1.0)]),
            vec![1, 2, 3, 4, 5],
        ],
    );
    assert!(routed.is_empty());
    let [packets, _, malformed, unknown, bad, applied, _] = rx.counters().snapshot();
    assert_eq!((packets, malformed, unknown, bad, applied), (4, 1, 1, 2, 0));
}

#[test]
fn out_of_range_values_are_clamped_when_applied() {
    let gpu = common::gpu();
    let k = scene("kleinian");
    let mut instance = SceneInstance::new(&gpu, &common::assets(), k.clone(), (32, 32)).unwrap();
    let (routed, _) = send_and_route(&k, &[packet("/indra/limit_set/scale", vec![OscType::Float(1e6)])]);
    let events: Vec<ControlEvent> =
        routed.into_iter().filter_map(|r| if let Routed::Event(e) = r { Some(e) } else { None }).collect();
    instance.apply(&events);
    let scale = instance.params(0).index("scale").unwrap();
    assert_eq!(instance.params(0).target_at(scale), ParamValue::Float(50.0));
}

#[test]
fn a_bundle_arrives_in_one_drain() {
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let content = (0..3)
        .map(|i| {
            OscPacket::Message(OscMessage {
                addr: "/indra/limit_set/scale".into(),
                args: vec![OscType::Float(i as f32)],
            })
        })
        .collect();
    let bundle = OscPacket::Bundle(OscBundle { timetag: OscTime { seconds: 0, fractional: 1 }, content });
    for _ in 0..50 {
        tx.send_to(&rosc::encoder::encode(&bundle).unwrap(), rx.local_addr()).unwrap();
    }
    let batches = receive(&mut rx, 50);
    assert_eq!(batches.len(), 50);
    assert!(batches.iter().all(|b| b.messages.len() == 3), "a bundle is never split across frames");
}

#[test]
fn a_future_time_tag_waits_until_due() {
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let due = SystemTime::now() + Duration::from_millis(400);
    let msg = OscPacket::Message(OscMessage { addr: "/indra/limit_set/scale".into(), args: vec![OscType::Float(2.0)] });
    let bundle = OscPacket::Bundle(OscBundle { timetag: OscTime::try_from(due).unwrap(), content: vec![msg] });
    tx.send_to(&rosc::encoder::encode(&bundle).unwrap(), rx.local_addr()).unwrap();
    assert!(receive(&mut rx, 1).is_empty(), "not yet due");
    std::thread::sleep(Duration::from_millis(450));
    assert_eq!(rx.drain(SystemTime::now()).len(), 1);
}

#[test]
fn far_future_and_flooding_bundles_are_dropped_and_counted() {
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let msg = OscPacket::Message(OscMessage { addr: "/indra/limit_set/scale".into(), args: vec![OscType::Float(2.0)] });
    let tagged = |timetag: OscTime| {
        rosc::encoder::encode(&OscPacket::Bundle(OscBundle { timetag, content: vec![msg.clone()] })).unwrap()
    };
    let bundle = |due: SystemTime| tagged(OscTime::try_from(due).unwrap());
    // A tag in 2100, past the 2036 NTP era rollover (its 32-bit seconds wrap; it used to apply at
    // once), and one a day ahead.
    let year_2100 = OscTime { seconds: ((4_102_444_800u64 + 2_208_988_800) % (1 << 32)) as u32, fractional: 0 };
    tx.send_to(&tagged(year_2100), rx.local_addr()).unwrap();
    tx.send_to(&bundle(SystemTime::now() + Duration::from_secs(86_400)), rx.local_addr()).unwrap();
    assert!(receive(&mut rx, 2).is_empty(), "neither applies now");
    assert_eq!(rx.counters().snapshot()[6], 2, "both dropped: more than an hour ahead");
    // More future bundles than the schedule holds: the rest are dropped, memory stays bounded.
    let soon = bundle(SystemTime::now() + Duration::from_secs(60));
    let extra = 500;
    for _ in 0..indra::control::osc::MAX_SCHEDULED + extra {
        tx.send_to(&soon, rx.local_addr()).unwrap();
    }
    let sent = 2 + (indra::control::osc::MAX_SCHEDULED + extra) as u64;
    assert!(receive(&mut rx, sent).is_empty());
    let dropped = rx.counters().snapshot()[6];
    assert!(dropped >= 2 + extra as u64, "dropped {dropped}");
}

#[test]
fn an_external_client_controls_a_parameter() {
    let k = scene("kleinian");
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let port = rx.local_addr().port().to_string();
    let status = std::process::Command::new("oscsend")
        .args(["127.0.0.1", &port, "/indra/limit_set/t", "ff", "1.95", "0.015"])
        .status()
        .expect("oscsend from liblo-tools (tools/test installs it)");
    assert!(status.success());
    let batches = receive(&mut rx, 1);
    let router = OscRouter::new(&k);
    let routed = router.route(&batches[0].messages[0], &k, &rx).unwrap();
    assert_eq!(write_value(&routed), ParamValue::Vec2([1.95, 0.015]));
}

/// A small deterministic generator (xorshift) for hostile input.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

#[test]
fn a_hundred_thousand_hostile_packets_never_panic() {
    let valid = [
        packet("/indra/limit_set/t", vec![OscType::Float(1.9), OscType::Float(0.02)]),
        rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
            timetag: OscTime { seconds: 0, fractional: 1 },
            content: vec![OscPacket::Message(OscMessage {
                addr: "/a".into(),
                args: vec![OscType::String("x".into())],
            })],
        }))
        .unwrap(),
    ];
    let (mut ok, mut err) = (0u32, 0u32);
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for i in 0..100_000 {
        let bytes: Vec<u8> = if i % 2 == 0 {
            let len = (xorshift(&mut state) % 96) as usize;
            (0..len).map(|_| xorshift(&mut state) as u8).collect()
        } else {
            // Truncated or corrupted valid packets.
            let v = &valid[i % valid.len()];
            let mut b = v[..(xorshift(&mut state) as usize % (v.len() + 1))].to_vec();
            if let Some(x) = b.get_mut(xorshift(&mut state) as usize % v.len()) {
                *x ^= xorshift(&mut state) as u8;
            }
            b
        };
        match decode(&bytes) {
            Ok(_) => ok += 1,
            Err(_) => err += 1,
        }
    }
    assert_eq!(ok + err, 100_000);
    assert!(err > 50_000, "most hostile packets are rejected ({err})");
    // And through the real socket: the counters add up.
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut sent = 0u64;
    for _ in 0..2000 {
        let len = 1 + (xorshift(&mut state) % 64) as usize;
        let bytes: Vec<u8> = (0..len).map(|_| xorshift(&mut state) as u8).collect();
        tx.send_to(&bytes, rx.local_addr()).unwrap();
        sent += 1;
    }
    let batches = receive(&mut rx, sent);
    let [packets, _, malformed, ..] = rx.counters().snapshot();
    assert_eq!(packets, sent);
    assert_eq!(malformed + batches.len() as u64, sent, "every packet is either a batch or counted malformed");
}

/// `inner` wrapped in `levels` bundles, as raw bytes (built by hand: rosc would recurse).
fn nested_bundles(inner: &[u8], levels: usize) -> Vec<u8> {
    let mut packet = inner.to_vec();
    for _ in 0..levels {
        let mut outer = b"#bundle\0".to_vec();
        outer.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1]);
        outer.extend_from_slice(&(packet.len() as u32).to_be_bytes());
        outer.extend_from_slice(&packet);
        packet = outer;
    }
    packet
}

#[test]
fn crafted_deep_nesting_is_malformed_and_the_show_goes_on() {
    // The packets that aborted the show: 2,500 nested bundles (≈ 50 KB, the OSC thread's stack)
    // and 15,000 nested arrays in a message to a real address (the render thread's stack).
    let k = scene("kleinian");
    let scale = packet("/indra/limit_set/scale", vec![OscType::Float(3.0)]);
    let bundles = nested_bundles(&scale, 2_500);
    assert!(bundles.len() < 65_000, "fits one datagram: {}", bundles.len());
    let mut arrays = b"/indra/limit_set/scale\0\0,".to_vec();
    arrays.extend(std::iter::repeat_n(b'[', 15_000).chain(std::iter::repeat_n(b']', 15_000)));
    arrays.push(0);
    while !arrays.len().is_multiple_of(4) {
        arrays.push(0);
    }
    let (routed, rx) = send_and_route(&k, &[bundles, arrays, nested_bundles(&scale, 4)]);
    let [_, _, malformed, ..] = rx.counters().snapshot();
    assert_eq!(malformed, 2, "both crafted packets are counted as malformed");
    assert_eq!(routed.len(), 1, "a sane nested bundle still applies");
    assert_eq!(write_value(&routed[0]), ParamValue::Float(3.0));
}

#[test]
fn feedback_sends_changed_values_to_the_controller() {
    let gpu = common::gpu();
    let mut instance = SceneInstance::new(&gpu, &common::assets(), scene("kleinian"), (32, 32)).unwrap();
    let listener = UdpSocket::bind("127.0.0.1:0").unwrap();
    listener.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    let feedback = OscFeedback::connect(&listener.local_addr().unwrap().to_string()).unwrap();
    let mut changes = ParamChanges::default();
    assert_eq!(feedback.send(&changes.collect(instance.view())), 11, "everything once at first");
    assert_eq!(feedback.send(&changes.collect(instance.view())), 0, "nothing changed");
    let mut buf = [0u8; 1024];
    for _ in 0..11 {
        listener.recv(&mut buf).unwrap();
    }
    let scale = instance.params(0).index("scale").unwrap();
    let write = indra::params::ParamWrite {
        node: 0,
        param: scale,
        component: None,
        value: ParamValue::Float(3.0),
        source: indra::params::Source::Midi,
    };
    instance.apply(&[ControlEvent::Write(write)]);
    assert_eq!(feedback.send(&changes.collect(instance.view())), 1);
    let n = listener.recv(&mut buf).unwrap();
    let (_, packet) = rosc::decoder::decode_udp(&buf[..n]).unwrap();
    assert_eq!(
        packet,
        OscPacket::Message(OscMessage { addr: "/indra/limit_set/scale".into(), args: vec![OscType::Float(3.0)] })
    );
}

pub(crate) fn http_get(addr: std::net::SocketAddr, path: &str) -> (u16, serde_json::Value) {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    write!(s, "GET {path} HTTP/1.0\r\nHost: localhost\r\n\r\n").unwrap();
    let mut response = String::new();
    s.read_to_string(&mut response).unwrap();
    let status = response[9..12].parse().unwrap();
    let body = response.split("\r\n\r\n").nth(1).unwrap_or("{}");
    (status, serde_json::from_str(body).unwrap())
}

#[test]
fn oscquery_serves_every_parameter_with_type_range_and_value() {
    // The protocol needs the scene and its values, not a device: no GPU is opened here.
    let star_glow = scene("star_glow");
    let values: Vec<indra::params::ParamSet> = star_glow.nodes.iter().map(|n| n.params.clone()).collect();
    let view =
        SceneView { scene: &star_glow, params: &values, tempo: indra::params::TempoClock::new(120.0), show: None };
    let server = OscQueryServer::start("127.0.0.1:0", 9000).unwrap();
    // Before the show publishes its scene, the tree is not shown as an empty one.
    assert_eq!(http_raw(server.local_addr(), b"GET / HTTP/1.1\r\n\r\n"), 503);
    assert_eq!(http_get(server.local_addr(), "/?HOST_INFO").0, 200);
    server.publish(view);
    let (status, tree) = http_get(server.local_addr(), "/");
    assert_eq!(status, 200);
    for (n, node) in view.scene.nodes.iter().enumerate() {
        let params = view.params(n);
        for (p, decl) in params.decls().iter().enumerate() {
            let leaf = &tree["CONTENTS"]["indra"]["CONTENTS"][&node.id]["CONTENTS"][&decl.name];
            assert_eq!(leaf["FULL_PATH"], format!("/indra/{}/{}", node.id, decl.name));
            assert_eq!(leaf["DESCRIPTION"], decl.doc);
            let value = params.target_at(p);
            match value {
                ParamValue::Enum(_) => {
                    assert_eq!(leaf["TYPE"], "s");
                    assert_eq!(leaf["VALUE"][0], decl.format(&value));
                    assert_eq!(leaf["RANGE"][0]["VALS"].as_array().unwrap().len(), decl.options.len());
                }
                ParamValue::Bool(b) => assert_eq!(leaf["VALUE"][0], b),
                ParamValue::Int(i) => {
                    assert_eq!((leaf["TYPE"].as_str(), leaf["VALUE"][0].as_i64()), (Some("i"), Some(i64::from(i))))
                }
                other => {
                    let got: Vec<f32> =
                        leaf["VALUE"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap() as f32).collect();
                    assert_eq!(got, other.components().to_vec(), "{}", decl.name);
                    assert_eq!(leaf["TYPE"].as_str().unwrap().len(), other.components().len());
                }
            }
            if let (Some((lo, hi)), false) = (decl.range, !decl.options.is_empty()) {
                assert_eq!(leaf["RANGE"][0]["MIN"].as_f64().unwrap() as f32, lo);
                assert_eq!(leaf["RANGE"][0]["MAX"].as_f64().unwrap() as f32, hi);
            }
        }
    }
    let (_, info) = http_get(server.local_addr(), "/?HOST_INFO");
    assert_eq!((info["OSC_PORT"].as_u64(), info["OSC_TRANSPORT"].as_str()), (Some(9000), Some("UDP")));
    let (_, leaf) = http_get(server.local_addr(), "/indra/glow/streaks");
    assert_eq!(leaf["VALUE"][0], 5);
    let (status, _) = http_get(server.local_addr(), "/indra/nothing");
    assert_eq!(status, 404);
}

/// Sends raw bytes, returns the status of the reply (0 if the connection was just closed).
fn http_raw(addr: std::net::SocketAddr, request: &[u8]) -> u16 {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let _ = s.write_all(request);
    let mut response = Vec::new();
    let _ = s.read_to_end(&mut response);
    String::from_utf8_lossy(&response).get(9..12).and_then(|c| c.parse().ok()).unwrap_or(0)
}

#[test]
fn oscquery_survives_hostile_http() {
    use std::io::{Read, Write};
    let server = OscQueryServer::start("127.0.0.1:0", 9000).unwrap();
    let addr = server.local_addr();
    // The request that aborted the show: a body of 99,999,999,999 bytes declared (never sent).
    assert_eq!(http_raw(addr, b"GET / HTTP/1.1\r\nContent-Length: 99999999999\r\n\r\n"), 413);
    assert_eq!(http_raw(addr, b"POST / HTTP/1.1\r\nContent-Length: 3\r\n\r\nabc"), 405);
    // 100 KB of headers: refused without reading on.
    let mut huge = b"GET / HTTP/1.1\r\n".to_vec();
    huge.extend(std::iter::repeat_n(b"X-Pad: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\r\n".as_slice(), 2000).flatten());
    assert_eq!(http_raw(addr, &huge), 431);
    // A client that stalls half-way through its headers does not hold up anyone else.
    let mut stalled = std::net::TcpStream::connect(addr).unwrap();
    stalled.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n").unwrap();
    let started = Instant::now();
    assert_eq!(http_get(addr, "/?HOST_INFO").0, 200);
    assert!(started.elapsed() < Duration::from_secs(1), "a stalled client delayed another one");
    // It is dropped after the timeout instead of holding a thread forever.
    stalled.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut rest = Vec::new();
    let closed = stalled.read_to_end(&mut rest).is_ok();
    assert!(closed && String::from_utf8_lossy(&rest).contains("408"), "{}", String::from_utf8_lossy(&rest));
    // A hundred idle connections: the server stays up and answers once they time out.
    let idle: Vec<_> = (0..100).map(|_| std::net::TcpStream::connect(addr).unwrap()).collect();
    std::thread::sleep(Duration::from_millis(2500));
    assert_eq!(http_get(addr, "/?HOST_INFO").0, 200);
    drop(idle);
}

#[test]
fn stats_are_answered_over_osc() {
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let client = UdpSocket::bind("127.0.0.1:0").unwrap();
    client.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    client.send_to(&[0xde, 0xad], rx.local_addr()).unwrap();
    client.send_to(&packet("/indra/stats", vec![]), rx.local_addr()).unwrap();
    let mut buf = [0u8; 512];
    let n = client.recv(&mut buf).unwrap();
    let (_, reply) = rosc::decoder::decode_udp(&buf[..n]).unwrap();
    let OscPacket::Message(m) = reply else { panic!("{reply:?}") };
    assert_eq!(m.addr, "/indra/stats");
    // packets, messages, malformed, unknown address, bad arguments, applied
    assert_eq!(m.args[..3], [OscType::Long(2), OscType::Long(1), OscType::Long(1)]);
    let _ = receive(&mut rx, 2);
}

/// The (node id, parameter name) each routed write goes to.
fn written(scene: &Scene, routed: &[Routed]) -> Vec<(String, String)> {
    routed
        .iter()
        .map(|r| match r {
            Routed::Event(ControlEvent::Write(w)) => {
                let node = &scene.nodes[w.node];
                (node.id.clone(), node.params.decls()[w.param].name.clone())
            }
            other => panic!("not a write: {other:?}"),
        })
        .collect()
}

#[test]
fn address_patterns_reach_every_parameter_they_match_and_no_command() {
    let s = scene("two_projectors");
    let pairs = |list: &[(&str, &str)]| list.iter().map(|(n, p)| (n.to_string(), p.to_string())).collect::<Vec<_>>();
    let (routed, rx) = send_and_route(&s, &[packet("/indra/output{1,2}/blend_curve", vec![OscType::Float(3.0)])]);
    assert_eq!(written(&s, &routed), pairs(&[("output1", "blend_curve"), ("output2", "blend_curve")]));
    assert!(routed.iter().all(|r| write_value(r) == ParamValue::Float(3.0)));
    assert_eq!(rx.counters().applied.load(std::sync::atomic::Ordering::Relaxed), 1);

    let (routed, _) =
        send_and_route(&s, &[packet("/indra/output?/corner_t[lr]", vec![OscType::Float(0.5), OscType::Float(0.5)])]);
    assert_eq!(
        written(&s, &routed),
        pairs(&[
            ("output1", "corner_tl"),
            ("output1", "corner_tr"),
            ("output2", "corner_tl"),
            ("output2", "corner_tr")
        ])
    );
    // An alias and a default address of one parameter are one write.
    let (routed, _) =
        send_and_route(&s, &[packet("/indra/output/*/corner/0", vec![OscType::Float(0.1), OscType::Float(0.9)])]);
    assert_eq!(written(&s, &routed), pairs(&[("output1", "corner_tl"), ("output2", "corner_tl")]));

    let (routed, rx) = send_and_route(
        &s,
        &[
            packet("/indra/record/*", vec![]),
            packet("/indra/preset/*", vec![OscType::String("a".into())]),
            packet("/indra/[", vec![OscType::Float(1.0)]),
            packet("/indra/*/blend_curve", vec![OscType::String("steep".into())]),
        ],
    );
    assert!(routed.is_empty(), "patterns never reach commands: {routed:?}");
    let counters = rx.counters().snapshot();
    assert_eq!((counters[3], counters[4]), (3, 1), "3 unknown, 1 with bad arguments: {counters:?}");
}

#[test]
fn a_flood_of_new_patterns_costs_a_bounded_amount_per_frame() {
    let s = scene("two_projectors");
    let packets: Vec<Vec<u8>> =
        (0..100).map(|i| packet(&format!("/indra/output{{1,x{i}}}/blend_curve"), vec![OscType::Float(2.5)])).collect();
    let (routed, rx) = send_and_route(&s, &packets);
    let new_patterns = indra::control::osc_route::NEW_PATTERNS_PER_FRAME;
    assert_eq!(routed.len(), new_patterns, "each routed pattern reaches output1 once");
    assert_eq!(rx.counters().snapshot()[3], (100 - new_patterns) as u64, "the rest are counted");
}

#[test]
fn tempo_is_set_and_tapped_over_osc() {
    let k = scene("kleinian");
    let (routed, rx) = send_and_route(
        &k,
        &[
            packet("/indra/tempo/bpm", vec![OscType::Float(128.0)]),
            packet("/indra/tempo/tap", vec![]),
            packet("/indra/tempo/bpm", vec![OscType::String("fast".into())]),
        ],
    );
    assert_eq!(routed, [Routed::Event(ControlEvent::Tempo { bpm: 128.0, resync: false }), Routed::TapTempo]);
    assert_eq!(rx.counters().snapshot()[4], 1, "the word is a bad argument");
}

/// Writes `value` to parameter `name` of node 0.
fn set(instance: &mut SceneInstance, name: &str, value: ParamValue) {
    let param = instance.params(0).index(name).unwrap();
    let write =
        indra::params::ParamWrite { node: 0, param, component: None, value, source: indra::params::Source::Osc };
    instance.apply(&[ControlEvent::Write(write)]);
}

pub(crate) type Socket = tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<std::net::TcpStream>>;

/// The next message within `wait`, skipping pings; None when none came.
pub(crate) fn next_message(socket: &mut Socket, wait: Duration) -> Option<tungstenite::Message> {
    if let tungstenite::stream::MaybeTlsStream::Plain(s) = socket.get_mut() {
        s.set_read_timeout(Some(wait)).unwrap();
    }
    loop {
        match socket.read() {
            Ok(tungstenite::Message::Ping(_) | tungstenite::Message::Pong(_)) => continue,
            Ok(m) => return Some(m),
            Err(_) => return None,
        }
    }
}

#[test]
fn oscquery_listen_sends_changes_of_listened_values_over_a_websocket() {
    use tungstenite::Message;
    let gpu = common::gpu();
    let mut instance = SceneInstance::new(&gpu, &common::assets(), scene("kleinian"), (32, 32)).unwrap();
    let mut server = OscQueryServer::start("127.0.0.1:0", 9000).unwrap();
    let mut changes = ParamChanges::default();
    let (_, info) = http_get(server.local_addr(), "/?HOST_INFO");
    assert_eq!(info["EXTENSIONS"]["LISTEN"], true);
    let (mut socket, _) = tungstenite::connect(format!("ws://{}/", server.local_addr())).unwrap();
    socket.send(Message::text(r#"{"COMMAND":"LISTEN","DATA":"/indra/limit_set/scale"}"#)).unwrap();
    // The session reads the command between polls: change the value until it is heard.
    let started = Instant::now();
    let heard = loop {
        assert!(started.elapsed() < Duration::from_secs(5), "no change arrived");
        set(&mut instance, "scale", ParamValue::Float(2.0 + started.elapsed().as_secs_f32()));
        server.after_frame(instance.view(), false, &changes.collect(instance.view()));
        if let Some(Message::Binary(bytes)) = next_message(&mut socket, Duration::from_millis(50)) {
            break rosc::decoder::decode_udp(&bytes).unwrap().1;
        }
    };
    let OscPacket::Message(m) = heard else { panic!("{heard:?}") };
    assert_eq!(m.addr, "/indra/limit_set/scale");
    assert!(matches!(m.args[..], [OscType::Float(v)] if v > 2.0), "{m:?}");
    // A value nobody listens to is not sent.
    while next_message(&mut socket, Duration::from_millis(100)).is_some() {}
    set(&mut instance, "iterations", ParamValue::Int(7));
    assert_eq!(
        server.after_frame(instance.view(), false, &changes.collect(instance.view())),
        0,
        "iterations changed, but nobody listens to it"
    );
    // After IGNORE, nothing more.
    socket.send(Message::text(r#"{"COMMAND":"IGNORE","DATA":"/indra/limit_set/scale"}"#)).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    set(&mut instance, "scale", ParamValue::Float(1.5));
    assert_eq!(server.after_frame(instance.view(), false, &changes.collect(instance.view())), 0, "ignored");
    assert!(next_message(&mut socket, Duration::from_millis(200)).is_none());
    // A new scene is announced once its tree is published.
    server.scene_changed();
    server.after_frame(instance.view(), false, &changes.collect(instance.view()));
    let Some(Message::Text(text)) = next_message(&mut socket, Duration::from_secs(2)) else {
        panic!("no PATH_CHANGED")
    };
    let said: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!((said["COMMAND"].as_str(), said["DATA"].as_str()), (Some("PATH_CHANGED"), Some("/indra")));
    // Garbage, unknown commands and huge messages end nothing but (at most) that session.
    socket.send(Message::text("not json")).unwrap();
    socket.send(Message::text(r#"{"COMMAND":"FLY","DATA":3}"#)).unwrap();
    let _ = socket.send(Message::binary(vec![0u8; 200_000]));
    assert_eq!(http_get(server.local_addr(), "/?HOST_INFO").0, 200, "the server still answers");
}

#[test]
fn oscquery_serves_a_bounded_number_of_websockets() {
    let server = OscQueryServer::start("127.0.0.1:0", 9000).unwrap();
    let url = format!("ws://{}/", server.local_addr());
    let open: Vec<_> = (0..indra::control::http::MAX_SOCKETS).map(|_| tungstenite::connect(&url).unwrap()).collect();
    match tungstenite::connect(&url) {
        Err(tungstenite::Error::Http(response)) => assert_eq!(response.status(), 503),
        other => panic!("one past the cap was let in: {:?}", other.map(|_| ())),
    }
    drop(open);
    // Closed sessions free their places.
    let started = Instant::now();
    while tungstenite::connect(&url).is_err() {
        assert!(started.elapsed() < Duration::from_secs(5), "places were not freed");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn oscquery_is_found_by_an_mdns_browser() {
    use mdns_sd::{ServiceDaemon, ServiceEvent};
    let server = OscQueryServer::start("0.0.0.0:0", 9123).unwrap();
    let browser = ServiceDaemon::new().unwrap();
    let found = |service: &str, port: u16| {
        let events = browser.browse(service).unwrap();
        let started = Instant::now();
        while started.elapsed() < Duration::from_secs(10) {
            if let Ok(ServiceEvent::ServiceResolved(info)) = events.recv_timeout(Duration::from_millis(200))
                && info.get_port() == port
                && info.get_fullname().starts_with("indra-")
            {
                return true;
            }
        }
        false
    };
    assert!(found(indra::control::discovery::OSCQUERY_SERVICE, server.local_addr().port()), "no _oscjson._tcp");
    assert!(found(indra::control::discovery::OSC_SERVICE, 9123), "no _osc._udp");
    let _ = browser.shutdown();
}

/// A TCP connection to `addr` from loopback address `from` (another machine on the venue network).
fn connect_from(from: &str, addr: std::net::SocketAddr) -> std::io::Result<std::net::TcpStream> {
    let socket = socket2::Socket::new(socket2::Domain::IPV4, socket2::Type::STREAM, None)?;
    socket.bind(&format!("{from}:0").parse::<std::net::SocketAddr>().unwrap().into())?;
    socket.connect(&addr.into())?;
    Ok(socket.into())
}

#[test]
fn slow_clients_on_one_machine_cannot_keep_oscquery_from_the_others() {
    use std::io::Write;
    use std::sync::atomic::{AtomicBool, Ordering};
    let server = OscQueryServer::start("127.0.0.1:0", 9000).unwrap();
    let addr = server.local_addr();
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    // 32 clients at 127.0.0.2, each sending one header byte every 1.5 s, reconnecting when cut off.
    let attack = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let mut slow: Vec<Option<std::net::TcpStream>> = (0..32).map(|_| None).collect();
            let mut cut_off = 0;
            while !stop.load(Ordering::Relaxed) {
                for conn in slow.iter_mut() {
                    let alive = conn.as_mut().is_some_and(|c| c.write_all(b"X").is_ok());
                    if !alive {
                        cut_off += usize::from(conn.is_some());
                        *conn = connect_from("127.0.0.2", addr).ok();
                    }
                }
                std::thread::sleep(Duration::from_millis(1500));
            }
            cut_off
        })
    };
    std::thread::sleep(Duration::from_millis(500));
    for _ in 0..4 {
        let started = Instant::now();
        assert_eq!(http_get(addr, "/?HOST_INFO").0, 200, "a client on another machine is served");
        assert!(started.elapsed() < Duration::from_secs(1), "and at once: {:?}", started.elapsed());
        std::thread::sleep(Duration::from_millis(1000));
    }
    stop.store(true, Ordering::Relaxed);
    let cut_off = attack.join().unwrap();
    assert!(cut_off > 0, "trickling heads are cut off at the deadline");
}

#[test]
fn websockets_stalled_mid_frame_are_closed_and_free_their_places() {
    use std::io::{Read, Write};
    let server = OscQueryServer::start("127.0.0.1:0", 9000).unwrap();
    let addr = server.local_addr();
    let url = format!("ws://{addr}/");
    // Every place taken by a client that sends two bytes of a frame header and stops.
    let stalled: Vec<std::net::TcpStream> = (0..indra::control::http::MAX_SOCKETS)
        .map(|_| {
            let mut s = std::net::TcpStream::connect(addr).unwrap();
            write!(
                s,
                "GET / HTTP/1.1\r\nHost: localhost\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
            )
            .unwrap();
            let mut answer = [0u8; 12];
            s.read_exact(&mut answer).unwrap();
            assert_eq!(&answer, b"HTTP/1.1 101");
            s.write_all(&[0x81, 0xfe]).unwrap();
            s
        })
        .collect();
    assert!(tungstenite::connect(&url).is_err(), "every place is taken");
    let started = Instant::now();
    let limit = indra::control::listen::SESSION_IDLE + Duration::from_secs(5);
    let (mut socket, _) = loop {
        match tungstenite::connect(&url) {
            Ok(connected) => break connected,
            Err(_) => assert!(started.elapsed() < limit, "stalled sessions kept their places"),
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    // A live client answers the pings by itself and stays past the idle limit.
    if let tungstenite::stream::MaybeTlsStream::Plain(s) = socket.get_mut() {
        s.set_read_timeout(Some(Duration::from_millis(100))).unwrap();
    }
    let stay = Instant::now();
    while stay.elapsed() < indra::control::listen::SESSION_IDLE + Duration::from_secs(2) {
        match socket.read() {
            Ok(_) => {}
            Err(tungstenite::Error::Io(e)) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => panic!("a live session was closed: {e}"),
        }
    }
    drop(stalled);
}

#[test]
fn the_osc_queue_is_bounded_in_bytes_under_a_flood_of_large_datagrams() {
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
    let big = OscPacket::Message(OscMessage {
        addr: "/indra/limit_set/scale".into(),
        args: vec![OscType::Blob(vec![7u8; 60_000])],
    });
    let bytes = rosc::encoder::encode(&big).unwrap();
    // 400 datagrams of 60 KB (24 MB) with no frame draining them.
    for _ in 0..400 {
        sender.send_to(&bytes, rx.local_addr()).unwrap();
        std::thread::sleep(Duration::from_micros(200));
    }
    std::thread::sleep(Duration::from_millis(300));
    let pending = rx.pending_bytes();
    assert!(pending <= indra::control::osc::MAX_QUEUED_BYTES, "{pending} bytes queued");
    let [packets, _, _, _, _, _, dropped] = rx.counters().snapshot();
    assert!(packets > 200 && dropped > 0, "{packets} packets, {dropped} dropped");
    let drained = rx.drain(SystemTime::now());
    assert!(!drained.is_empty());
    assert_eq!(rx.pending_bytes(), 0, "a drain gives the bytes back");
}

/// A server with the browser surface: OSC from the sessions it admits goes into `rx`.
fn surface(read_only: bool, rx: &OscReceiver) -> OscQueryServer {
    surface_with(read_only, rx, &indra::control::site::SiteRules::default())
}

/// [`surface`] answering the names and third-party origins of `sites` too.
fn surface_with(read_only: bool, rx: &OscReceiver, sites: &indra::control::site::SiteRules) -> OscQueryServer {
    use indra::control::web::{AccessToken, WebOptions};
    let token = AccessToken::chosen("socket-test-token").unwrap();
    let web = WebOptions { addr: "127.0.0.1:0".into(), read_only, token, sessions: 4 };
    OscQueryServer::start_with("127.0.0.1:0", 0, Some((web, rx.inlet())), sites).unwrap()
}

/// Whether the session was closed by the server within a few seconds.
fn closed(socket: &mut Socket) -> bool {
    let started = Instant::now();
    while started.elapsed() < Duration::from_secs(5) {
        match next_message(socket, Duration::from_millis(200)) {
            Some(tungstenite::Message::Close(_)) => return true,
            Some(_) => {}
            None if socket.can_read() => {}
            None => return true,
        }
    }
    false
}

#[test]
fn websocket_osc_is_taken_only_with_the_token_and_within_the_limits_of_udp() {
    use tungstenite::Message;
    let mut rx = OscReceiver::without_socket();
    let server = surface(false, &rx);
    let at = server.local_addr();
    let write = packet("/indra/glow/intensity", vec![OscType::Float(0.5)]);

    // With the token (in the URL, or the cookie the page sets), packets are OSC like UDP's.
    let (mut socket, _) = tungstenite::connect(format!("ws://{at}/?token=socket-test-token")).unwrap();
    socket.send(Message::binary(write.clone())).unwrap();
    socket.send(Message::binary(b"garbage, not OSC".to_vec())).unwrap();
    let batches = receive(&mut rx, 2);
    assert_eq!(batches.len(), 1);
    assert_eq!(batches[0].messages[0].addr, "/indra/glow/intensity");
    let [packets, _, malformed, ..] = rx.counters().snapshot();
    assert_eq!((packets, malformed), (2, 1), "garbage is counted as UDP's is, and the session goes on");
    socket.send(Message::binary(write.clone())).unwrap();
    assert_eq!(receive(&mut rx, 3).len(), 1, "the session survived the garbage");
    let mut request = tungstenite::client::IntoClientRequest::into_client_request(format!("ws://{at}/")).unwrap();
    request.headers_mut().insert("Cookie", "indra_token=socket-test-token".parse().unwrap());
    let (mut cookie, _) = tungstenite::connect(request).unwrap();
    cookie.send(Message::binary(write.clone())).unwrap();
    assert_eq!(receive(&mut rx, 4).len(), 1);

    // Without it a session may LISTEN, but OSC closes it unapplied.
    let (mut stranger, _) = tungstenite::connect(format!("ws://{at}/?token=guess-guess-guess")).unwrap();
    stranger.send(Message::text(r#"{"COMMAND":"LISTEN","DATA":"/indra/glow/intensity"}"#)).unwrap();
    stranger.send(Message::binary(write.clone())).unwrap();
    assert!(closed(&mut stranger), "a session without the token kept writing");
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(rx.counters().snapshot()[0], 4, "its packet reached the show");

    // A huge frame and a flood end that session only.
    let _ = socket.send(Message::binary(vec![0u8; indra::control::http::MAX_SOCKET_MESSAGE + 1]));
    assert!(closed(&mut socket), "a huge frame did not end the session");
    let (mut flood, _) = tungstenite::connect(format!("ws://{at}/?token=socket-test-token")).unwrap();
    let sent = (0..5 * indra::control::listen::MAX_PACKET_RATE)
        .take_while(|_| flood.send(Message::binary(write.clone())).is_ok())
        .count();
    assert!(closed(&mut flood), "a flood of {sent} packets did not end the session");
    let taken = rx.counters().snapshot()[0];
    assert!(
        taken <= 4 + u64::from(indra::control::listen::MAX_PACKET_RATE) + 1,
        "{taken} packets taken from the flood"
    );
    cookie.send(Message::binary(write.clone())).unwrap();
    let started = Instant::now();
    while rx.counters().snapshot()[0] == taken {
        assert!(started.elapsed() < Duration::from_secs(5), "another session was hurt by the flood");
        std::thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(http_get(at, "/?HOST_INFO").0, 200, "the server still answers");

    // A read-only surface takes OSC from nobody, token or not.
    let mut rx = OscReceiver::without_socket();
    let server = surface(true, &rx);
    let (mut viewer, _) =
        tungstenite::connect(format!("ws://{}/?token=socket-test-token", server.local_addr())).unwrap();
    viewer.send(Message::binary(write)).unwrap();
    assert!(closed(&mut viewer));
    assert!(rx.drain(SystemTime::now()).is_empty());
}

/// The status and head of the reply to `request` (a whole request head).
fn http_head(addr: std::net::SocketAddr, request: &str) -> (u16, String) {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    s.write_all(request.as_bytes()).unwrap();
    let mut response = Vec::new();
    // A WebSocket that was let in stays open: the head is all there is to read.
    let mut chunk = [0u8; 4096];
    while let Ok(n) = s.read(&mut chunk) {
        response.extend_from_slice(&chunk[..n]);
        if n == 0 || response.windows(4).any(|w| w == b"\r\n\r\n") {
            break;
        }
    }
    let text = String::from_utf8_lossy(&response).to_string();
    let head = text.split("\r\n\r\n").next().unwrap_or_default().to_string();
    (text.get(9..12).and_then(|c| c.parse().ok()).unwrap_or(0), head)
}

#[test]
fn only_the_servers_own_names_and_pages_of_its_own_or_allowed_origins_are_answered() {
    use tungstenite::Message;
    let sites = indra::control::site::SiteRules { hosts: vec![], cors: vec!["http://127.0.0.1:5173".into()] };
    let mut rx = OscReceiver::without_socket();
    let server = surface_with(false, &rx, &sites);
    let at = server.local_addr();
    let upgrade = |host: &str, origin: &str| {
        format!(
            "GET /?token=socket-test-token HTTP/1.1\r\nHost: {host}\r\nOrigin: {origin}\r\nUpgrade: websocket\r\n\
             Connection: Upgrade\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
             Cookie: indra_token=socket-test-token\r\n\r\n"
        )
    };
    let own = format!("http://{at}");
    // DNS rebinding: another name for this address is answered nothing — tree, value, socket.
    for path in ["/", "/?HOST_INFO", "/indra/glow/intensity?VALUE", "/?token=socket-test-token"] {
        let request = format!("GET {path} HTTP/1.1\r\nHost: evil.example:{}\r\nAccept: text/html\r\n\r\n", at.port());
        assert_eq!(http_head(at, &request).0, 421, "{path}");
    }
    assert_eq!(http_head(at, &upgrade(&format!("evil.example:{}", at.port()), &own)).0, 421);
    // Its own names are answered.
    for host in [at.to_string(), format!("localhost:{}", at.port())] {
        assert_eq!(http_head(at, &format!("GET /?HOST_INFO HTTP/1.1\r\nHost: {host}\r\n\r\n")).0, 200, "{host}");
    }
    // A page of another site (another port of this very host too) opens no socket, cookie or not.
    for origin in ["http://evil.example", &format!("http://127.0.0.1:{}", at.port() + 1), "null"] {
        assert_eq!(http_head(at, &upgrade(&at.to_string(), origin)).0, 403, "{origin}");
    }
    assert_eq!(http_head(at, &upgrade(&at.to_string(), &own)).0, 101, "the surface's own page");
    // An allowed third-party client reads the tree across origins and, with the token, writes.
    let (_, head) =
        http_head(at, &format!("GET /?HOST_INFO HTTP/1.1\r\nHost: {at}\r\nOrigin: http://127.0.0.1:5173\r\n\r\n"));
    assert!(head.contains("Access-Control-Allow-Origin: http://127.0.0.1:5173"), "{head}");
    let (_, head) =
        http_head(at, &format!("GET /?HOST_INFO HTTP/1.1\r\nHost: {at}\r\nOrigin: http://evil.example\r\n\r\n"));
    assert!(!head.contains("Access-Control-Allow-Origin"), "{head}");
    let connect = |query: &str| {
        let mut request =
            tungstenite::client::IntoClientRequest::into_client_request(format!("ws://{at}/{query}")).unwrap();
        request.headers_mut().insert("Origin", "http://127.0.0.1:5173".parse().unwrap());
        tungstenite::connect(request).map(|(socket, _)| socket)
    };
    let write = packet("/indra/glow/intensity", vec![OscType::Float(0.5)]);
    let mut reader = connect("").expect("an allowed origin opens a socket");
    reader.send(Message::binary(write.clone())).unwrap();
    assert!(closed(&mut reader), "an allowed origin without the token wrote");
    let mut writer = connect("?token=socket-test-token").unwrap();
    writer.send(Message::binary(write)).unwrap();
    assert_eq!(receive(&mut rx, 1).len(), 1, "with the token it controls the show");
}

#[test]
fn a_third_party_oscquery_client_reads_the_tree_through_the_site_checks() {
    // npm's `oscquery` (jangxx/node-oscquery), installed by tools/test under target/.
    let Some(client) = std::env::var_os("INDRA_OSCQUERY_CLIENT") else {
        assert!(std::env::var_os("CI").is_none(), "CI runs the OSCQuery client test: INDRA_OSCQUERY_CLIENT is unset");
        return eprintln!("skipped: no OSCQuery client (tools/setup-oscquery-client installs it)");
    };
    let star_glow = scene("star_glow");
    let values: Vec<indra::params::ParamSet> = star_glow.nodes.iter().map(|n| n.params.clone()).collect();
    let view =
        SceneView { scene: &star_glow, params: &values, tempo: indra::params::TempoClock::new(120.0), show: None };
    let rx = OscReceiver::without_socket();
    let sites = indra::control::site::SiteRules { hosts: vec![], cors: vec!["http://127.0.0.1:5173".into()] };
    let server = surface_with(false, &rx, &sites);
    server.publish(view);
    let script = format!(
        "const {{ OSCQueryDiscovery }} = require('oscquery');
         new OSCQueryDiscovery().queryNewService('{host}', {port}).then(s => {{
           console.log(JSON.stringify({{ port: s.hostInfo.oscPort, paths: s.flat().map(m => m.full_path) }}));
           process.exit(0);
         }}, e => {{ console.error(String(e)); process.exit(1); }});",
        host = "localhost",
        port = server.local_addr().port()
    );
    let out = std::process::Command::new("node")
        .arg("-e")
        .arg(&script)
        .env("NODE_PATH", std::path::Path::new(&client).join("node_modules"))
        .output()
        .expect("node runs (the machine image has it)");
    assert!(out.status.success(), "the client failed: {}", String::from_utf8_lossy(&out.stderr));
    let said: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let paths: Vec<&str> = said["paths"].as_array().unwrap().iter().filter_map(|p| p.as_str()).collect();
    for node in &star_glow.nodes {
        for decl in node.params.decls() {
            let path = format!("/indra/{}/{}", node.id, decl.name);
            assert!(paths.contains(&path.as_str()), "the client misses {path}: {paths:?}");
        }
    }
    assert_eq!(said["port"], 0, "HOST_INFO's OSC port as served");
}
