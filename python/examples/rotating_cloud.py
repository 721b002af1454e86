#!/usr/bin/env python3
"""A rotating point cloud on the volumetric display.

A cloud of points (a trefoil knot with some scatter, coloured along the
knot) is sent once, in one display list; each frame only the layer's
transform changes: a turn about the vertical axis and a slow tumble. The
animation is paced by frame callbacks: the next transform is committed once
the previous one is on the display.

    rotating_cloud.py [--socket PATH] [--seconds S] [--points N] [--rpm R]

Exits 0 after S seconds (default: until interrupted), 1 when spindled
cannot be reached or the connection breaks.
"""
import argparse
import math
import sys
import time

import numpy as np

import spindle
from spindle import transform


def make_cloud(n, rng):
    """n points around a trefoil knot, inside the unit ball, and a colour per point (uint8 RGB)."""
    t = rng.uniform(0, 2 * math.pi, n)
    knot = np.stack([np.sin(t) + 2 * np.sin(2 * t), -np.sin(3 * t), np.cos(t) - 2 * np.cos(2 * t)], axis=1)
    knot /= 3.2
    points = knot + rng.normal(scale=0.04, size=(n, 3))
    hue = t / (2 * math.pi)
    colors = np.stack([np.abs(np.sin(math.pi * (hue + k / 3))) for k in range(3)], axis=1)
    return points.astype(np.float32), (64 + 191 * colors).astype(np.uint8)


def main(argv=None):
    ap = argparse.ArgumentParser(description='A rotating point cloud on the volumetric display, paced by frame '
                                 'callbacks.')
    ap.add_argument('--socket', help="spindled's socket (default: $SPINDLE_SOCKET, else /run/spindle/spindle.sock)")
    ap.add_argument('--seconds', type=float, default=0, help='run this long, then exit 0 (default: until interrupted)')
    ap.add_argument('--points', type=int, default=4000, help='points in the cloud (default 4000)')
    ap.add_argument('--rpm', type=float, default=6, help='turns of the cloud a minute (default 6)')
    args = ap.parse_args(argv)
    if args.points < 1:
        ap.error('--points must be at least 1')

    try:
        sp = spindle.connect(args.socket)
    except spindle.Error as e:
        print(f'rotating_cloud: {e}', file=sys.stderr)
        return 1
    with sp:
        dev = sp.device
        print(f'rotating_cloud: {dev.name}, {dev.images_per_rev} images of {dev.width}x{dev.height}, '
              f'h = {dev.half_height:g}, protocol version {sp.version}')
        points, colors = make_cloud(args.points, np.random.default_rng(1))
        # Fit the cloud's bounding sphere in the volume: radius 1, height 2h.
        fit = 0.95 * min(1.0, dev.half_height) / float(np.linalg.norm(points, axis=1).max())
        cloud = sp.create_list()
        if sp.version >= 2:
            cloud.set_point_size(2).points(points * fit, colors)
        else:
            cloud.points(points * fit)
        layer = sp.create_layer(cloud)

        frames = 0
        start = time.monotonic()
        try:
            while args.seconds <= 0 or time.monotonic() - start < args.seconds:
                t = time.monotonic() - start
                layer.transform = transform.rotate_y(2 * math.pi * args.rpm / 60 * t) @ transform.rotate_x(
                    0.3 * math.sin(0.5 * t))
                shown = sp.request_frame()
                sp.commit()
                shown.wait(timeout=5)
                frames += 1
        except KeyboardInterrupt:
            pass
        except spindle.Error as e:
            print(f'rotating_cloud: {e}', file=sys.stderr)
            return 1
        elapsed = time.monotonic() - start
        print(f'rotating_cloud: {frames} frames shown in {elapsed:.1f} s ({frames / max(elapsed, 1e-9):.1f} a second)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
