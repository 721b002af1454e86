#!/usr/bin/env python3
"""A 4-D CT on the volumetric display: the phases of a breathing cycle.

A chest-like phantom (int16, Hounsfield-like units: air -1000, soft tissue
40, lungs -800, a denser spot 200 that rides with the breath) is made in
PHASES phases of one breathing cycle: the lungs and the chest swell and
the spot moves up and down. Each phase is sent to the daemon once, as a
volume; then the display cycles through them by redrawing one list with
another volume each frame, nothing uploaded again, paced by frame
callbacks (a 4-D CT is typically 10 phases cycled at about 1 Hz; this
shows them as fast as the display takes them, or at --rate).

    breathing.py [--socket PATH] [--seconds S] [--phases N] [--size N] [--rate HZ]

Prints the phases shown a second and exits 0 after S seconds (default:
until interrupted); 1 when spindled cannot be reached or the connection
breaks.
"""
import argparse
import math
import sys
import time

import numpy as np

import spindle
from spindle import transform


def phase_volume(n, phase):
    """Samples [z, y, x] of one phase (0..1 of the cycle) of an n^3 chest."""
    g = (np.arange(n, dtype=np.float32) + 0.5) / n * 2 - 1  # -1..1
    z, y, x = np.meshgrid(g, g, g, indexing='ij')
    breath = 0.5 - 0.5 * math.cos(2 * math.pi * phase)   # 0 exhaled .. 1 inhaled
    v = np.full((n, n, n), -1000, dtype=np.int16)
    chest = (x / (0.75 + 0.08 * breath))**2 + (y / 0.9)**2 + (z / (0.55 + 0.06 * breath))**2 <= 1
    v[chest] = 40
    for side in (-1, 1):
        lung = ((x - side * 0.33) / (0.25 + 0.05 * breath))**2 + ((y - 0.1) / (0.55 + 0.12 * breath))**2 + \
            (z / (0.35 + 0.04 * breath))**2 <= 1
        v[lung] = -800
    spot = (x - 0.3)**2 + (y + 0.25 - 0.2 * breath)**2 + z**2 <= 0.1**2
    v[spot] = 200
    return v


def main(argv=None):
    ap = argparse.ArgumentParser(description='A 4-D CT: the phases of a breathing cycle, each sent once, cycled '
                                 'on the display.')
    ap.add_argument('--socket', help="spindled's socket (default: $SPINDLE_SOCKET, else /run/spindle/spindle.sock)")
    ap.add_argument('--seconds', type=float, default=0, help='run this long, then exit 0 (default: until interrupted)')
    ap.add_argument('--phases', type=int, default=10, help='phases in the cycle (default 10)')
    ap.add_argument('--size', type=int, default=64, help='samples along each axis (default 64)')
    ap.add_argument('--rate', type=float, default=0, help='phases a second at most (default: as fast as shown)')
    args = ap.parse_args(argv)
    if args.phases < 1 or not 2 <= args.size <= 512:
        ap.error('--phases must be at least 1 and --size 2 to 512')

    try:
        sp = spindle.connect(args.socket)
    except spindle.Error as e:
        print(f'breathing: {e}', file=sys.stderr)
        return 1
    with sp:
        if sp.version < 6:
            print(f'breathing: spindled speaks protocol {sp.version}; volumes need 6', file=sys.stderr)
            return 1
        dev = sp.device
        # The unit cube of samples, fitted: 1.3 across (its corners within
        # the display's radius), 1.8 h high, centred.
        spacing = (1.0 / args.size,) * 3
        fit = transform.scale(1.3, 1.8 * dev.half_height, 1.3) @ transform.translate(-0.5, -0.5, -0.5)
        start = time.monotonic()
        volumes = [sp.volume(phase_volume(args.size, i / args.phases), spacing) for i in range(args.phases)]
        print(f'breathing: {args.phases} phases of {args.size}^3 int16 sent in '
              f'{time.monotonic() - start:.2f} s', flush=True)
        lst = sp.create_list()
        sp.create_layer(lst)
        shown = 0
        pending = []
        start = time.monotonic()
        try:
            while args.seconds <= 0 or time.monotonic() - start < args.seconds:
                # A new phase: the list redrawn with another volume, no upload.
                lst.clear()
                lst.set_transform(fit)
                lst.set_color(255, 255, 255)
                lst.draw_volume(volumes[shown % args.phases], 'nearest', threshold=-900, window=(-300, 700))
                # Two commits in flight: the next phase is being rendered
                # while the last one waits for its revolution.
                pending.append(sp.request_frame())
                sp.commit()
                if len(pending) > 1:
                    pending.pop(0).wait(timeout=10)
                    shown += 1
                if args.rate > 0:
                    time.sleep(max(0.0, start + shown / args.rate - time.monotonic()))
        except KeyboardInterrupt:
            pass
        except spindle.Error as e:
            print(f'breathing: {e}', file=sys.stderr)
            return 1
        elapsed = time.monotonic() - start
        print(f'breathing: {shown} phases shown in {elapsed:.1f} s ({shown / max(elapsed, 1e-9):.1f} a second)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
