"""The official LCM library's side of crates/lcm's interoperability tests.

Driven by tests/official.rs and tests/netns.rs; every mode reads or writes JSON. A message value is
written as JSON by its type (lcm-gen's __slots__/__typenames__/__dimensions__): integers and bytes
as numbers, booleans as booleans, a double as "d:" and its 16 hex digits of IEEE bits, a float as
"f:" and 8, a string as itself, an array as a list (the innermost dimension of a byte array too),
a struct as an object. The Rust side writes the same form, so the two compare exactly.

Modes:
  samples GEN OUT            hand-made messages of every coopnav type: type, fingerprint, bytes, value
  decode GEN IN OUT          decode each {type, bytes}; write its value and its re-encoding
  fingerprints GEN OUT M.C.. packed fingerprints of the named generated classes
  log-read PATH OUT          every event lcm.EventLog reads from PATH
  log-write PATH IN          write {channel, timestamp, data} events with lcm.EventLog
  publish URL IN SECONDS     publish each {channel, data} every 0.1 s until SECONDS pass
  subscribe URL IN OUT SECS  subscribe to the channels in IN, print "ready", write the first
                             payload per channel to OUT once all came, or fail after SECS
"""

import importlib
import json
import math
import struct
import sys
import time


def load_class(typename):
    package, _, name = typename.rpartition(".")
    module = importlib.import_module(package) if package else importlib.import_module(name)
    return getattr(module, name)


def scalar_to_json(value, typename):
    if typename == "double":
        return "d:%016x" % struct.unpack(">Q", struct.pack(">d", value))[0]
    if typename == "float":
        return "f:%08x" % struct.unpack(">I", struct.pack(">f", value))[0]
    if typename == "boolean":
        return bool(value)
    if typename in ("int8_t", "int16_t", "int32_t", "int64_t", "byte"):
        return int(value)
    if typename == "string":
        return value
    return to_json(value)


def walk_to_json(value, typename, dims):
    if not dims:
        return scalar_to_json(value, typename)
    if typename == "byte" and len(dims) == 1:
        return list(value)
    return [walk_to_json(v, typename, dims[1:]) for v in value]


def to_json(msg):
    dims_of = msg.__dimensions__
    return {
        slot: walk_to_json(getattr(msg, slot), t, dims_of[i] or [])
        for i, (slot, t) in enumerate(zip(msg.__slots__, msg.__typenames__))
    }


def scalar_from_json(j, typename):
    if typename == "double":
        return struct.unpack(">d", bytes.fromhex(j[2:]))[0]
    if typename == "float":
        return struct.unpack(">f", bytes.fromhex(j[2:]))[0]
    if typename in ("int8_t", "int16_t", "int32_t", "int64_t", "byte", "boolean", "string"):
        return j
    return from_json(load_class(typename), j)


def walk_from_json(j, typename, dims):
    if not dims:
        return scalar_from_json(j, typename)
    if typename == "byte" and len(dims) == 1:
        return bytes(j)
    return [walk_from_json(v, typename, dims[1:]) for v in j]


def from_json(cls, j):
    msg = cls()
    for i, (slot, t) in enumerate(zip(cls.__slots__, cls.__typenames__)):
        setattr(msg, slot, walk_from_json(j[slot], t, cls.__dimensions__[i] or []))
    return msg


def decision(c, **fields):
    """A decision_t with the given fields and a tally of hand-picked values."""
    m = c.decision_t()
    m.seq, m.outcome, m.levels_requested, m.levels_searched, m.nodes = 41, c.decision_t.OUTCOME_PLANNED, 5, 4, 2**40
    m.elapsed_s, m.fix_utime, m.n_status = 0.0123, 1_700_000_000_000_000, 12
    m.decisions, m.deadline_misses, m.failures, m.waiting = 42, 1, 2, 3
    m.min_levels_searched, m.mean_levels_searched = 3, 4.75
    for k, v in fields.items():
        setattr(m, k, v)
    return m


def samples():
    """Hand-made messages, values chosen by hand (edges, unicode, NaN and infinities)."""
    import coopnav as c

    def make(cls, **fields):
        m = cls()
        for k, v in fields.items():
            setattr(m, k, v)
        return m

    pos = make(c.position_t, x=1.5, y=-2.25, z=30.0)
    est = [
        make(c.auv_estimate_t, utime=10, auv=1, x=100.0, y=-50.0, cov=[[4.0, 0.25], [0.25, 9.0]], valid=True),
        make(c.auv_estimate_t, utime=-(2**63), auv=-32768, x=-0.0, y=math.inf, cov=[[math.nan, 0.0], [1e-300, -1e300]], valid=False),
    ]
    return [
        pos,
        make(c.cna_fix_t, utime=1_700_000_000_123_456, x=1234.5, y=-987.25, depth=0.5, heading=math.pi, variance=9.0, source=c.cna_fix_t.SOURCE_GPS),
        make(c.status_frame_t, utime=2**63 - 1, src=-7, receive_time=3600.000125, n=6, data=bytes([0, 1, 127, 128, 254, 255])),
        make(c.status_frame_t, utime=0, src=0, receive_time=0.0, n=0, data=b""),
        make(c.owtt_range_t, utime=42, src=-128, transmit_time=100.0, receive_time=100.5, transponder=pos, travel_time=0.666),
        make(c.cna_command_t, utime=5, seq=17, has_waypoint=True, heading=-1.0, waypoint_x=500.0, waypoint_y=-250.0, waypoint_depth=2.0, speed=1.75),
        make(c.cna_command_t, utime=6, seq=-1, has_waypoint=False, heading=0.1, waypoint_x=0.0, waypoint_y=0.0, waypoint_depth=-0.0, speed=3.4028234663852886e38),
        decision(c, utime=7, n_options=3, option_turn=[-0.5, 0.0, 0.5], option_pitch=[0.0, 0.0, 0.0], option=2, cost=2.5, policy="planner-estimator"),
        decision(c, utime=8, n_options=0, option_turn=[], option_pitch=[], option=-1, cost=math.nan, policy=""),
        decision(c, utime=9, n_options=1, option_turn=[math.inf], option_pitch=[-1e-300], option=0, cost=-math.inf, policy="ünïcode Ω 波 \U0001F30A"),
        est[0],
        est[1],
        make(c.auv_sensors_t, utime=11, auv=3, heading=2.0, speed=1.5, depth=35.25, dvl_lock=True,
             dvl_beam_range=[10.0, 11.5, -1.0, 1e-38], n_samples=2, sample_utime=[1, -1],
             sample_velocity=[[1.0, 0.0, -0.5], [0.25, 0.125, 2.0]]),
        make(c.auv_sensors_t, utime=12, auv=4, heading=0.0, speed=0.0, depth=0.0, dvl_lock=False,
             dvl_beam_range=[0.0, 0.0, 0.0, 0.0], n_samples=0, sample_utime=[], sample_velocity=[]),
        make(c.clock_t, utime=13, tick=123456789, dt=0.1, running=True),
        make(c.team_estimate_t, utime=14, n=2, auvs=est, names=["auv-1", "Ωb"], flags=[b"\x01\x02", b"\xff\x00"]),
        make(c.team_estimate_t, utime=15, n=0, auvs=[], names=[], flags=[b"", b""]),
    ]


def main():
    mode = sys.argv[1]
    if mode in ("samples", "decode", "fingerprints"):
        sys.path.insert(0, sys.argv[2])
    if mode == "samples":
        out = []
        for m in samples():
            t = type(m)
            typename = t.__module__.rpartition(".")[0] + "." + t.__name__
            out.append({
                "type": typename,
                "fingerprint": t._get_packed_fingerprint().hex(),
                "bytes": m.encode().hex(),
                "value": to_json(m),
            })
        json.dump(out, open(sys.argv[3], "w"))
    elif mode == "decode":
        out = []
        for item in json.load(open(sys.argv[3])):
            cls = load_class(item["type"])
            m = cls.decode(bytes.fromhex(item["bytes"]))
            out.append({"value": to_json(m), "reencoded": m.encode().hex()})
        json.dump(out, open(sys.argv[4], "w"))
    elif mode == "fingerprints":
        json.dump({n: load_class(n)._get_packed_fingerprint().hex() for n in sys.argv[4:]}, open(sys.argv[3], "w"))
    elif mode == "log-read":
        import lcm
        log = lcm.EventLog(sys.argv[2], "r")
        out = [{"eventnum": e.eventnum, "timestamp": e.timestamp, "channel": e.channel, "data": e.data.hex()} for e in log]
        json.dump(out, open(sys.argv[3], "w"))
    elif mode == "log-write":
        import lcm
        log = lcm.EventLog(sys.argv[2], "w", overwrite=True)
        for e in json.load(open(sys.argv[3])):
            log.write_event(e["timestamp"], e["channel"], bytes.fromhex(e["data"]))
        log.close()
    elif mode == "publish":
        import lcm
        lc = lcm.LCM(sys.argv[2])
        messages = [(m["channel"], bytes.fromhex(m["data"])) for m in json.load(open(sys.argv[3]))]
        deadline = time.monotonic() + float(sys.argv[4])
        while time.monotonic() < deadline:
            for channel, data in messages:
                lc.publish(channel, data)
            time.sleep(0.1)
    elif mode == "subscribe":
        import lcm
        lc = lcm.LCM(sys.argv[2])
        wanted = json.load(open(sys.argv[3]))
        got = {}

        def handler(channel, data):
            got.setdefault(channel, data.hex())

        for channel in wanted:
            lc.subscribe(channel, handler)
        print("ready", flush=True)
        deadline = time.monotonic() + float(sys.argv[5])
        while len(got) < len(wanted) and time.monotonic() < deadline:
            lc.handle_timeout(100)
        json.dump(got, open(sys.argv[4], "w"))
        sys.exit(0 if len(got) == len(wanted) else 1)
    else:
        sys.exit("unknown mode " + mode)


if __name__ == "__main__":
    main()
