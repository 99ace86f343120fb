"""Compare the recorded payloads of two MCAP files topic by topic: are they byte-identical?

    .venv/bin/python tools/compare_recordings.py BEFORE.mcap AFTER.mcap

Prints one line per topic (message counts, ``identical`` or the index and stamp of the first
differing message) and exits 0 when every topic of both files is identical, 1 otherwise. Used
for issue 30's oracle 4: with the current off, every recording stays byte-identical to the
one made before currents existed (run both with a long ``lockstep_timeout_s``: a lockstep
timeout under load steps once on a stale command and changes every later payload).
"""

from __future__ import annotations

import sys
from collections import defaultdict

from uvms_recording.mcap_reader import open_recording


def payloads(path: str) -> dict[str, list[tuple[int, bytes]]]:
    """{topic: [(log time ns, CDR bytes), ...]} of a recording, in log-time order."""
    out: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    for message in open_recording(path).messages():
        out[message.topic].append((message.log_time_ns, message.data))
    return out


def main(argv: list[str]) -> int:
    """Print the per-topic comparison; 0 if every topic is byte-identical."""
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    first, second = payloads(argv[0]), payloads(argv[1])
    same = True
    for topic in sorted(set(first) | set(second)):
        a, b = first.get(topic, []), second.get(topic, [])
        verdict = 'identical'
        if [data for _, data in a] != [data for _, data in b]:
            same = False
            pairs = enumerate(zip(a, b, strict=False))
            k = next((i for i, (x, y) in pairs if x[1] != y[1]), min(len(a), len(b)))
            when = f', logged at {a[k][0] * 1e-9:.3f} s' if k < len(a) else ''
            verdict = f'DIFFERENT from message {k}{when}'
        print(f'{topic:36s} {len(a):7d} {len(b):7d}  {verdict}')
    return 0 if same else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
