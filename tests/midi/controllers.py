"""Simulated pad controllers on real JACK MIDI ports, for indra's tests.

Each device named on the command line (NAME=OUT_PORT,IN_PORT) is a JACK client with a MIDI
output (what its pads and faders send) and input (the lights it is sent). Commands on stdin,
one per line; each answers one line of JSON on stdout:
  send NAME HEX       send the bytes (one or more messages) from NAME's output
  take NAME           every message NAME received since the last take: [[seconds, hex], ...]
  mtc NAME FPS FRAME  run MTC quarter frames at FPS (24, 25 or 30: no drop-frame) from frame
                      count FRAME (even) on; answers the wall-clock time FRAME began
  mtc-stop NAME       stop the MTC (a dropout, or a desk that stops)
  play NAME FILE PORTS  play FILE (unsigned 8-bit mono samples at the server's rate, as
                      tests/timecode/ltcgen.c writes LTC) from an audio output of NAME's,
                      connected to every audio input whose name matches the regex PORTS;
                      silence after its end
  played NAME         where the playing file was at each cycle since the last ask:
                      [[wall-clock seconds, sample index], ...]
  record NAME PORTS   record an audio input of NAME's, connected from every audio output
                      whose name matches the regex PORTS
  recorded NAME FILE  write what was recorded to FILE (signed 16-bit mono samples, as
                      tests/timecode/ltcread.c reads them) and answer where each cycle began:
                      [[monotonic seconds, as MIDI arrivals are stamped, sample index], ...]
  unplug NAME         close NAME's client (its ports vanish, as a USB device's do)
  plug NAME           open it again
  quit
"""

import array
import json
import queue
import sys
import time

import jack


class Device:
    def __init__(self, name, out_port, in_port):
        self.name, self.out_port, self.in_port = name, out_port, in_port
        self.client = None
        self.outgoing = queue.Queue()
        self.received = queue.Queue()
        # A running MTC: (fps, first quarter, wall-clock time of the first, quarters sent).
        self.mtc = None
        # A playing file: (samples as floats, next index), its audio port, and the cycles' stamps.
        self.playing = None
        self.audio = None
        self.cycles = queue.Queue()
        # A recording: its audio port, the samples (floats), and each cycle's stamp.
        self.recorder = None
        self.recording = None

    def plug(self):
        client = jack.Client(self.name, no_start_server=True)
        output = client.midi_outports.register(self.out_port)
        inport = client.midi_inports.register(self.in_port)

        def process(frames):
            output.clear_buffer()
            while True:
                try:
                    data = self.outgoing.get_nowait()
                except queue.Empty:
                    break
                output.write_midi_event(0, data)
            self.run_mtc(output)
            self.play(frames)
            # Stamped on the wall clock when the cycle runs (JACK's frame clock runs behind it
            # on a busy machine, where the server waits for late clients).
            now = time.monotonic()
            self.record(now)
            for _, data in inport.incoming_midi_events():
                self.received.put((now, bytes(data).hex()))

        client.set_process_callback(process)
        client.activate()
        self.client = client

    def run_mtc(self, output):
        """Sends the quarter frames due by now (each at its time, to the cycle)."""
        if self.mtc is None:
            return
        fps, first, began, sent = self.mtc
        due = first + int((time.time() - began) * fps * 4) + 1
        for quarter in range(first + sent, due):
            output.write_midi_event(0, quarter_frame(quarter, fps))
        self.mtc = (fps, first, began, max(sent, due - first))

    def play(self, frames):
        """Writes this cycle's samples of the playing file (silence past its end)."""
        if self.audio is None:
            return
        buffer = self.audio.get_buffer()
        buffer[:] = bytes(len(buffer))
        if self.playing is None:
            return
        samples, at = self.playing
        chunk = samples[at:at + frames].tobytes()
        buffer[:len(chunk)] = chunk
        self.playing = (samples, at + frames)
        # Stamped on the wall clock as the MTC is: the cycle's first sample goes out now.
        self.cycles.put((time.time(), at))

    def record(self, now):
        """Keeps this cycle's samples of the recorded input, stamped."""
        if self.recording is None:
            return
        samples, stamps = self.recording
        stamps.append((now, len(samples) // 4))
        samples.extend(self.recorder.get_buffer())

    def start_recording(self, ports):
        if self.recorder is None:
            self.recorder = self.client.inports.register("record")
        for port in self.client.get_ports(ports, is_audio=True, is_output=True):
            self.client.connect(port, self.recorder)
        self.recording = (bytearray(), [])

    def write_recording(self, path):
        samples, stamps = self.recording
        self.recording = None
        floats = array.array("f")
        floats.frombytes(bytes(samples))
        pcm = array.array("h", (max(-32767, min(32767, int(x * 32767))) for x in floats))
        with open(path, "wb") as f:
            f.write(pcm.tobytes())
        return stamps

    def start_playing(self, path, ports):
        with open(path, "rb") as f:
            samples = array.array("f", ((b - 128) / 160 for b in f.read()))
        if self.audio is None:
            self.audio = self.client.outports.register("audio")
        for port in self.client.get_ports(ports, is_audio=True, is_input=True):
            self.client.connect(self.audio, port)
        self.playing = (samples, 0)

    def unplug(self):
        self.client.deactivate()
        self.client.close()
        self.client = None

    def send(self, hex_bytes):
        data = bytes.fromhex(hex_bytes)
        # One JACK event per channel message (3 bytes) or SysEx.
        i = 0
        while i < len(data):
            if data[i] == 0xF0:
                end = data.index(0xF7, i) + 1
            else:
                end = i + (2 if data[i] & 0xF0 in (0xC0, 0xD0) else 3)
            self.outgoing.put(data[i:end])
            i = end

    def take(self):
        out = []
        while True:
            try:
                out.append(self.received.get_nowait())
            except queue.Empty:
                return out


def quarter_frame(quarter, fps):
    """MTC quarter frame number `quarter` (from frame count 0) at a rate without drop-frame."""
    piece = quarter % 8
    frame = (quarter - piece) // 4
    seconds, frames = divmod(frame, fps)
    minutes, seconds = divmod(seconds, 60)
    hours, minutes = divmod(minutes, 60)
    rate_code = {24: 0, 25: 1, 30: 3}[fps]
    value = [frames, seconds, minutes, hours][piece // 2]
    nibble = value & 0xF if piece % 2 == 0 else value >> 4
    if piece == 7:
        nibble |= rate_code << 1
    return bytes([0xF1, piece << 4 | nibble])


def main():
    devices = {}
    for spec in sys.argv[1:]:
        name, ports = spec.split("=", 1)
        out_port, in_port = ports.split(",", 1)
        devices[name] = Device(name, out_port, in_port)
        devices[name].plug()
    print(json.dumps("ready"), flush=True)
    for line in sys.stdin:
        words = line.strip().split(" ")
        command, name = words[0], " ".join(words[1:2])
        if command == "quit":
            break
        device = devices[name.replace("_", " ")]
        if command == "send":
            device.send(words[2])
            answer = "sent"
        elif command == "take":
            answer = device.take()
        elif command == "mtc":
            fps, frame = int(words[2]), int(words[3])
            began = time.time()
            device.mtc = (fps, frame * 4, began, 0)
            answer = began
        elif command == "play":
            device.start_playing(words[2], words[3])
            answer = "playing"
        elif command == "played":
            answer = []
            while not device.cycles.empty():
                answer.append(device.cycles.get_nowait())
        elif command == "record":
            device.start_recording(words[2])
            answer = "recording"
        elif command == "recorded":
            answer = device.write_recording(words[2])
        elif command == "mtc-stop":
            device.mtc = None
            answer = "stopped"
        elif command == "unplug":
            device.unplug()
            answer = "unplugged"
        elif command == "plug":
            device.plug()
            answer = "plugged"
        else:
            answer = "unknown command"
        print(json.dumps(answer), flush=True)


if __name__ == "__main__":
    main()
