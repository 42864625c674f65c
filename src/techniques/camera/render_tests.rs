//! The camera node end to end with ffmpeg's test pattern standing in for a device (the same
//! reader, arguments aside), and with a device this machine does not have.

use crate::common::{assets, gpu, read_float_texture};
use indra::graph::{FrameGraph, GraphRuntime};
use indra::params::ParamSet;
use indra::scene::parse_value_override;
use indra::techniques::{NodeSetup, camera};
use indra::time::FrameTime;

fn params(settings: &[(&str, &str)]) -> ParamSet {
    let mut params = ParamSet::new(camera::Settings::decls());
    for (name, value) in settings {
        let i = params.index(name).unwrap();
        params.set_at(i, parse_value_override(value, &params.decls()[i]).unwrap());
    }
    params
}

#[test]
fn the_test_pattern_comes_through_the_camera_node_and_a_missing_camera_is_one_sentence() {
    let gpu = gpu();
    let assets = assets();
    let size = (64, 48);
    let run = |settings: &[(&str, &str)], frames: usize| {
        let params = params(settings);
        let setup =
            NodeSetup { gpu: &gpu, assets: &assets, id: "cam", output_size: size, msaa: 1, params: &params, seed: 1 };
        let mut node = (camera::INFO.create)(&setup).unwrap();
        let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        let mut images = Vec::new();
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
        for frame in 0..frames as u64 {
            let time = FrameTime { frame, seconds: frame as f64 / 30.0, dt: 1.0 / 30.0, seed: 1 };
            node.step(&params, &time);
            let mut graph = FrameGraph::new(size);
            let out = node.add_passes(&mut graph, &params, &time, &[]);
            graph.set_output(out);
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let result = runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).unwrap();
            gpu.queue.submit([encoder.finish()]);
            images.push(read_float_texture(&gpu, &result.texture));
            // Live input: give the camera thread time to deliver, as a show's frames would.
            if std::time::Instant::now() < deadline {
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
        }
        (images, node.take_messages())
    };

    let (images, messages) = run(&[("device", "test"), ("width", "64"), ("height", "48"), ("fit", "stretch")], 20);
    assert!(messages.is_empty(), "{messages:?}");
    let last = images.last().unwrap();
    assert!(last.iter().any(|p| p[0] > 0.2) && last.iter().any(|p| p[0] < 0.05), "the test pattern, not black or flat");
    assert!(images.windows(2).any(|w| w[0] != w[1]), "the pattern moves");

    let (images, messages) = run(&[("device", "/dev/video987")], 10);
    assert!(images.iter().all(|i| i.iter().all(|p| *p == [0.0; 4])), "black without the camera");
    assert_eq!(messages.len(), 1, "one sentence, not one per frame: {messages:?}");
    assert!(messages[0].starts_with("no camera at /dev/video987"), "{messages:?}");
}
