"""The other end of indra's sACN tests: PyPI's sacn (tools/setup-dmx-peer installs it).

receive ADDR PORT SECONDS  -- parses every E1.31 packet arriving on ADDR:PORT with sacn's own
                              parsers (data and synchronisation packets) and prints one JSON line:
                              each data packet's universe, priority, sequence, sync address and
                              first channels, and each sync packet's address and sequence.
send ADDR UNIVERSE SECONDS CH=V...  -- sacn's sender: unicast to ADDR, the channels given (1-based),
                              at its own rate, for SECONDS.
"""
import json
import socket
import sys
import time


def receive(addr, port, seconds):
    from sacn.messages.data_packet import DataPacket
    from sacn.messages.sync_packet import SyncPacket

    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((addr, port))
    sock.settimeout(0.2)
    data, syncs, other = [], [], 0
    end = time.time() + seconds
    while time.time() < end:
        try:
            raw = sock.recv(2048)
        except socket.timeout:
            continue
        raw = tuple(raw)
        try:
            p = DataPacket.make_data_packet(raw)
            data.append({"universe": p.universe, "priority": p.priority, "sequence": p.sequence,
                         "sync": p.syncAddr, "channels": list(p.dmxData[:64])})
            continue
        except Exception:
            pass
        try:
            s = SyncPacket.make_sync_packet(raw)
            syncs.append({"sync": s.syncAddr, "sequence": s.sequence})
        except Exception:
            other += 1
    print(json.dumps({"data": data, "syncs": syncs, "other": other}))


def send(addr, universe, seconds, pairs):
    import sacn

    # Any port of its own: the receiver under test holds 5568.
    sender = sacn.sACNsender(bind_address="127.0.0.1", bind_port=0, fps=30)
    sender.start()
    sender.activate_output(universe)
    sender[universe].destination = addr
    channels = [0] * 512
    for pair in pairs:
        ch, value = pair.split("=")
        channels[int(ch) - 1] = int(value)
    sender[universe].dmx_data = tuple(channels)
    time.sleep(seconds)
    sender.stop()
    print(json.dumps({"sent": True}))


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "receive":
        receive(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]))
    elif mode == "send":
        send(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5:])
    else:
        sys.exit(f"unknown mode {mode}")
