"""The other end of indra's NDI tests: cyndilib's sender and receiver (PyPI's cyndilib ships the
NDI runtime), run inside a network namespace of their own so nothing is announced on the
machine's real network.

    unshare --net --map-root-user python3 peer.py receive OUT_DIR -- indra render ... --ndi-out indra-out
    unshare --net --map-root-user python3 peer.py receive-live OUT_DIR -- indra run ... --ndi-out indra-out
    unshare --net --map-root-user python3 peer.py send OUT_DIR -- indra render ...

Discovery: the runtime finds sources by mDNS through an avahi daemon, which a bare namespace
lacks; an NDI configuration naming 127.0.0.1 among the machines to ask ("networks.ips") makes
every finder ask the loopback address directly. This script writes that configuration, points
NDI_CONFIG_DIR at it (for itself and for indra), brings the loopback interface up, runs its side
and indra, and prints one JSON line of what it saw.
"""

import json
import os
import subprocess
import sys
import time

import numpy as np

# The pattern `send` sends: four quadrants, so a flipped or shifted picture shows.
QUADRANTS = [(230, 40, 40), (40, 200, 60), (50, 70, 220), (240, 220, 60)]
SEND_SIZE = (96, 64)


def prepare(out_dir):
    """Loopback up, the unicast discovery configuration in place, for this process and indra."""
    subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
    config = os.path.join(out_dir, "ndi-config")
    os.makedirs(config, exist_ok=True)
    with open(os.path.join(config, "ndi-config.v1.json"), "w") as f:
        json.dump({"ndi": {"networks": {"ips": "127.0.0.1"}}}, f)
    os.environ["NDI_CONFIG_DIR"] = config


def start_indra(command, out_dir):
    log = open(os.path.join(out_dir, "indra.log"), "w")
    return subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)


def find(name_suffix, until, alive):
    """The source whose name ends with `name_suffix`, once the finder sees it."""
    from cyndilib.finder import Finder

    finder = Finder()
    finder.open()
    while time.time() < until and alive():
        finder.wait_for_sources(0.5)
        for name in finder.get_source_names():
            if name.endswith(name_suffix):
                return finder, finder.get_source(name)
    return finder, None


def receive(out_dir, command, keep=8, live=False):
    """Receives indra's source `indra-out`: `keep` frames (NDI_PEER_KEEP overrides), the first
    eight saved as raw RGBA files named by the frame number their timecode carries, and each
    frame's delivery latency (its arrival against the timestamp the sending library stamped it
    with: one machine, one clock). A `live` indra (a window) is then stopped with SIGTERM, as a
    service manager would."""
    from cyndilib.receiver import Receiver, ReceiveFrameType
    from cyndilib.video_frame import VideoRecvFrame
    from cyndilib.wrapper.ndi_recv import RecvBandwidth, RecvColorFormat

    keep = int(os.environ.get("NDI_PEER_KEEP", keep))
    indra = start_indra(command, out_dir)
    until = time.time() + 40 + keep / 30
    finder, source = find("(indra-out)", until, lambda: indra.poll() is None)
    result = {"found": source is not None, "frames": [], "latency_ms": []}
    if source is not None:
        receiver = Receiver(color_format=RecvColorFormat.RGBX_RGBA, bandwidth=RecvBandwidth.highest)
        video = VideoRecvFrame(max_buffers=2)
        receiver.set_video_frame(video)
        receiver.set_source(source)
        while indra.poll() is None and len(result["latency_ms"]) < keep and time.time() < until:
            kind = receiver.receive(ReceiveFrameType.recv_video, 200)
            if not kind & ReceiveFrameType.recv_video:
                continue
            arrived = time.time()
            # The frame's fields describe the capture just made: take its pixels at once.
            if video.get_buffer_depth() != 1:
                video.skip_frames(True)
                continue
            result["latency_ms"].append((arrived - video.get_timestamp_posix()) * 1000.0)
            pixels = np.array(video, dtype=np.uint8)
            if len(result["frames"]) >= 8:
                continue
            rate = video.get_frame_rate()
            frame = round(video.get_timecode_posix() * rate.numerator / rate.denominator)
            path = os.path.join(out_dir, f"received_{frame:05}.rgba")
            pixels.tofile(path)
            result["frames"].append({
                "frame": frame,
                "size": [video.xres, video.yres],
                "fourcc": video.get_fourcc().name,
                "file": path,
            })
        receiver.disconnect()
    finder.close()
    if live and indra.poll() is None:
        indra.terminate()
    indra.wait(timeout=120)
    result["indra_exit"] = indra.returncode
    print(json.dumps(result))


def quadrants(w, h):
    img = np.zeros((h, w, 4), np.uint8)
    img[..., 3] = 255
    for i, (r, g, b) in enumerate(QUADRANTS):
        ys = slice(0, h // 2) if i < 2 else slice(h // 2, h)
        xs = slice(0, w // 2) if i % 2 == 0 else slice(w // 2, w)
        img[ys, xs, 0], img[ys, xs, 1], img[ys, xs, 2] = b, g, r  # BGRA
    return img


def send(out_dir, command, seconds=3.0):
    """Sends the quadrant pattern as `pysend` for `seconds` after indra starts, then withdraws
    it while indra goes on; also runs `indra --list-ndi` while the source is up."""
    from cyndilib.sender import Sender
    from cyndilib.video_frame import VideoSendFrame
    from cyndilib.wrapper.ndi_structs import FourCC
    from fractions import Fraction

    w, h = SEND_SIZE
    sender = Sender("pysend")
    frame = VideoSendFrame()
    frame.set_resolution(w, h)
    frame.set_fourcc(FourCC.BGRA)
    frame.set_frame_rate(Fraction(30, 1))
    sender.set_video_frame(frame)
    image = quadrants(w, h).ravel()
    result = {"sent": 0}
    with sender:
        listed = subprocess.run(command[:1] + ["--list-ndi"], capture_output=True, text=True, timeout=60)
        result["list_ndi"] = listed.stdout + listed.stderr
        # indra connects by the address --list-ndi printed: its own sender (--ndi-out, which paces
        # the render) makes its finder list only its own process's sources when no mDNS daemon
        # runs, as in this namespace.
        url = next((line.split()[-1] for line in listed.stdout.splitlines() if "(pysend)" in line), "")
        indra = start_indra([arg.replace("{url}", url) for arg in command], out_dir)
        start = time.time()
        while time.time() - start < seconds and indra.poll() is None:
            sender.write_video(image)
            result["sent"] += 1
            time.sleep(1 / 30)
    indra.wait(timeout=120)
    result["indra_exit"] = indra.returncode
    print(json.dumps(result))


if __name__ == "__main__":
    mode, out_dir = sys.argv[1], sys.argv[2]
    command = sys.argv[sys.argv.index("--") + 1:]
    prepare(out_dir)
    modes = {"receive": receive, "receive-live": lambda o, c: receive(o, c, live=True), "send": send}
    modes[mode](out_dir, command)
