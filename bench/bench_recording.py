"""Benchmark of MCAP recording: write and read throughput for the graph's 1 kHz message mix.

Prints figures; asserts nothing. The mix is one JointState, one Odometry and one
ControllerState per 1 ms step (what the recorder sees from a 1 kHz lockstep run), serialized
once by rosbags; the timed part is McapRecorder.write (+ close) and reading back.

Run: .venv/bin/python bench/bench_recording.py [--seconds S]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'src' / 'uvms_bringup'))

from uvms_model.description import load_description  # noqa: E402
from uvms_recording.mcap_reader import open_recording  # noqa: E402
from uvms_recording.mcap_writer import McapRecorder  # noqa: E402
from uvms_recording.typestore import uvms_typestore  # noqa: E402

#: The paper robot's arm joints, read from its URDF.
JOINTS = list(load_description().joint_names)

MIX = (
    ('/uvms/joint_states', 'sensor_msgs/msg/JointState'),
    ('/uvms/odometry', 'nav_msgs/msg/Odometry'),
    ('/uvms/controller/state', 'uvms_msgs/msg/ControllerState'),
)


def _messages(seconds: float) -> list[tuple[str, int, bytes]]:
    """(topic, log time ns, CDR) for `seconds` of the 1 kHz mix, with varying values."""
    store = uvms_typestore()
    types = store.types
    time_ = types['builtin_interfaces/msg/Time']
    header = types['std_msgs/msg/Header']
    vec = types['geometry_msgs/msg/Vector3']
    point = types['geometry_msgs/msg/Point']
    rng = np.random.default_rng(0)
    out = []
    for k in range(round(seconds * 1000)):
        t_ns = k * 1_000_000
        stamp = time_(sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        q = rng.normal(size=3)
        joint_state = types['sensor_msgs/msg/JointState'](
            header=header(stamp=stamp, frame_id=''),
            name=JOINTS,
            position=q, velocity=rng.normal(size=3), effort=rng.normal(size=3),
        )
        pose = types['geometry_msgs/msg/Pose'](
            position=point(x=q[0], y=q[1], z=q[2]),
            orientation=types['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0),
        )
        twist = types['geometry_msgs/msg/Twist'](linear=vec(x=q[0], y=0.0, z=0.0),
                                                 angular=vec(x=0.0, y=0.0, z=q[1]))
        odometry = types['nav_msgs/msg/Odometry'](
            header=header(stamp=stamp, frame_id='map_ned'),
            child_frame_id='base_link_frd',
            pose=types['geometry_msgs/msg/PoseWithCovariance'](pose=pose,
                                                               covariance=np.zeros(36)),
            twist=types['geometry_msgs/msg/TwistWithCovariance'](twist=twist,
                                                                 covariance=np.zeros(36)),
        )
        v = [vec(x=a, y=b, z=c) for a, b, c in rng.normal(size=(8, 3))]
        state = types['uvms_msgs/msg/ControllerState'](
            header=header(stamp=stamp, frame_id='map_ned'), weight=float(rng.random()),
            phase=1, contact_force=v[0], desired_force=v[1],
            position=point(x=q[0], y=q[1], z=q[2]), desired_position=point(x=0.0, y=0.0,
                                                                           z=0.0),
            velocity=v[2], desired_velocity=v[3], normal_velocity=float(q[0]),
            impedance_force=v[4], hybrid_force=v[5], command_force=v[6],
        )
        for (topic, type_name), message in zip(MIX, (joint_state, odometry, state),
                                               strict=True):
            out.append((topic, t_ns, bytes(store.serialize_cdr(message, type_name))))
    return out


def main() -> None:
    """Print write and read throughput for zstd, lz4 and no compression."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seconds', type=float, default=20.0,
                        help='simulated seconds of the 1 kHz mix (default 20)')
    args = parser.parse_args()
    messages = _messages(args.seconds)
    payload = sum(len(data) for _, _, data in messages)
    print(f'{len(messages)} messages ({args.seconds:g} s of 3 topics at 1 kHz), '
          f'{payload / 1e6:.1f} MB of CDR, mean {payload / len(messages):.0f} B')
    print(f'{"compression":<12} {"write msg/s":>12} {"write MB/s":>11} {"file MB":>8} '
          f'{"ratio":>6} {"read msg/s":>11} {"read MB/s":>10}')
    with tempfile.TemporaryDirectory() as tmp:
        for compression in ('zstd', 'lz4', 'none'):
            path = Path(tmp) / f'{compression}.mcap'
            start = time.perf_counter()
            with McapRecorder(path, compression=compression) as recorder:  # type: ignore[arg-type]
                for topic, type_name in MIX:
                    recorder.add_topic(topic, type_name)
                for topic, t_ns, data in messages:
                    recorder.write(topic, data, t_ns)
            write_s = time.perf_counter() - start
            size = path.stat().st_size
            start = time.perf_counter()
            count = sum(1 for _ in open_recording(path).messages())
            read_s = time.perf_counter() - start
            if count != len(messages):
                raise SystemExit(f'read {count} messages back from {path}, wrote {len(messages)}')
            print(f'{compression:<12} {len(messages) / write_s:>12,.0f} '
                  f'{payload / write_s / 1e6:>11.1f} {size / 1e6:>8.2f} '
                  f'{payload / size:>6.2f} {len(messages) / read_s:>11,.0f} '
                  f'{payload / read_s / 1e6:>10.1f}')


if __name__ == '__main__':
    main()
