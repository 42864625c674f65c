//! Live-loop benchmarks (criterion): sustained OSC throughput over loopback UDP with every
//! message accounted for, and the latency from saving a shader to the first frame rendered
//! with it (goal ≤ 150 ms). Run: `cargo bench --bench live`.

use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant, SystemTime};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use indra::assets::Assets;
use indra::control::osc::OscReceiver;
use indra::control::osc_route::OscRouter;
use indra::gpu::{Gpu, GpuOptions};
use indra::live::LiveReload;
use indra::offscreen::OffscreenRenderer;
use indra::scene::load_scene;
use rosc::{OscMessage, OscPacket, OscType};

const MESSAGES: u64 = 20_000;
/// Messages per burst; bursts are sent every BURST_GAP (≈ 128k messages/s offered).
const BURST: u64 = 256;
const BURST_GAP: Duration = Duration::from_millis(2);

/// Offers MESSAGES messages in bursts at a sustained ≈128k/s while the render side drains and
/// routes them; returns the time until the last one was routed. Any drop fails the bench.
fn osc_round(rx: &mut OscReceiver, router: &OscRouter, scene: &indra::scene::Scene) -> Duration {
    let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
    let target = rx.local_addr();
    let start_count = rx.counters().applied.load(Ordering::Relaxed);
    let sender = std::thread::spawn(move || {
        for i in 0..MESSAGES {
            let msg = OscMessage {
                addr: "/indra/limit_set/scale".into(),
                args: vec![OscType::Float((i % 40) as f32 * 0.1 + 1.0)],
            };
            tx.send_to(&rosc::encoder::encode(&OscPacket::Message(msg)).unwrap(), target).unwrap();
            if i % BURST == BURST - 1 {
                std::thread::sleep(BURST_GAP);
            }
        }
    });
    let start = Instant::now();
    let mut routed = 0;
    while routed < MESSAGES && start.elapsed() < Duration::from_secs(10) {
        for batch in rx.drain(SystemTime::now()) {
            for m in &batch.messages {
                routed += u64::from(router.route(m, scene, rx).is_some());
            }
        }
        std::thread::sleep(Duration::from_micros(500));
    }
    let elapsed = start.elapsed();
    sender.join().unwrap();
    let applied = rx.counters().applied.load(Ordering::Relaxed) - start_count;
    assert_eq!(applied, MESSAGES, "dropped {} of {MESSAGES} messages", MESSAGES - applied);
    elapsed
}

fn osc_throughput(c: &mut Criterion) {
    let assets = Assets::new(Some(env!("CARGO_MANIFEST_DIR").into()));
    let scene = load_scene(&assets, "kleinian").unwrap();
    let mut rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let router = OscRouter::new(&scene);
    let mut group = c.benchmark_group("osc");
    group.throughput(Throughput::Elements(MESSAGES));
    group.sample_size(10);
    group.bench_function("udp_receive_decode_route_20k", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| osc_round(&mut rx, &router, &scene)).sum())
    });
    group.finish();
}

fn copy_assets(root: &Path) {
    for dir in ["scenes", "shaders"] {
        std::fs::create_dir_all(root.join(dir)).unwrap();
        for e in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(dir)).unwrap().flatten() {
            std::fs::copy(e.path(), root.join(dir).join(e.file_name())).unwrap();
        }
    }
    // The technique's own shader, as a performer's copy in shaders/ that the bench edits.
    let kleinian = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/techniques/kleinian/kleinian.wgsl");
    std::fs::copy(kleinian, root.join("shaders/kleinian.wgsl")).unwrap();
}

fn reload_latency(c: &mut Criterion) {
    let root: PathBuf = std::env::temp_dir().join(format!("indra-bench-reload-{}", std::process::id()));
    copy_assets(&root);
    let assets = Assets::new(Some(root.clone()));
    let scene = load_scene(&assets, "kleinian_classic").unwrap();
    let gpu = Gpu::headless(&GpuOptions::default()).unwrap();
    let mut renderer = OffscreenRenderer::new(gpu, &assets, scene, Some((256, 256)), None, None).unwrap();
    let mut live = LiveReload::new(&assets).unwrap();
    let shader = root.join("shaders/kleinian.wgsl");
    let original = std::fs::read_to_string(&shader).unwrap();
    let mut generation = 0u64;
    let mut group = c.benchmark_group("hot_reload");
    group.sample_size(10);
    group.bench_function("save_shader_to_new_frame", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                generation += 1;
                std::fs::write(&shader, format!("{original}\n// edit {generation}\n")).unwrap();
                let saved = Instant::now();
                while renderer.poll_reload(&mut live).applied.is_empty() {
                    assert!(saved.elapsed() < Duration::from_secs(5), "the edit was never picked up");
                    std::thread::sleep(Duration::from_millis(1));
                }
                renderer.render_next().unwrap();
                total += saved.elapsed();
            }
            total
        })
    });
    group.finish();
    let _ = std::fs::remove_dir_all(root);
}

criterion_group!(benches, osc_throughput, reload_latency);
criterion_main!(benches);
