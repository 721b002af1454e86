#!/usr/bin/env python3
"""A plot of a function z = f(x, y) as a surface in the volumetric display.

The function is sampled on a grid over -1 <= x, y <= 1, drawn as an indexed
triangle mesh fitted in the display's volume (x and y across, f up the
rotation axis) and coloured by height, from blue (lowest) through green to
red (highest). It stays on the display until the time is up or it is
interrupted.

    surface.py [--socket PATH] [--function NAME | --expr EXPR] [--grid N] [--seconds S]

--expr takes a numpy expression in x and y (for instance
"np.sin(3 * x) * np.cos(3 * y)"); it is evaluated as Python, so only give
it expressions you trust. Exits 0 when done, 1 when spindled cannot be
reached or refuses the surface.
"""
import argparse
import math
import sys
import time

import numpy as np

import spindle

FUNCTIONS = {
    'ripple': lambda x, y: np.cos(6 * np.hypot(x, y)) * np.exp(-1.5 * np.hypot(x, y)),
    'saddle': lambda x, y: x * x - y * y,
    'peaks': lambda x, y: (3 * (1 - 3 * x)**2 * np.exp(-(3 * x)**2 - (3 * y + 1)**2) - 10 *
                           (3 * x / 5 - (3 * x)**3 - (3 * y)**5) * np.exp(-(3 * x)**2 - (3 * y)**2) -
                           np.exp(-(3 * x + 1)**2 - (3 * y)**2) / 3),
    'gauss': lambda x, y: np.exp(-4 * (x * x + y * y)),
}


def grid_mesh(f, n):
    """Samples f on an n x n grid over [-1, 1]^2: (xs, ys, zs) arrays and the triangles (M x 3 indices)."""
    u = np.linspace(-1, 1, n)
    x, y = np.meshgrid(u, u, indexing='ij')
    z = np.broadcast_to(np.asarray(f(x, y), dtype=np.float64), x.shape)
    i = np.arange(n * n).reshape(n, n)
    a, b, c, d = i[:-1, :-1].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel(), i[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return x.ravel(), y.ravel(), z.ravel(), triangles


def height_colours(t):
    """Colours for heights t in 0..1: blue, cyan, green, yellow, red (uint8 RGB)."""
    stops = np.array([[0, 0, 255], [0, 255, 255], [0, 255, 0], [255, 255, 0], [255, 0, 0]], dtype=np.float64)
    pos = np.clip(t, 0, 1) * (len(stops) - 1)
    k = np.minimum(pos.astype(int), len(stops) - 2)
    w = (pos - k)[:, None]
    return np.round(stops[k] * (1 - w) + stops[k + 1] * w).astype(np.uint8)


def fit_surface(x, y, z, half_height):
    """Volume-space vertices: the grid's square inscribed in the unit disk
    (a margin left), the function's range over 90% of the height."""
    side = 0.97 / math.sqrt(2)
    zmin, zmax = float(np.min(z)), float(np.max(z))
    span = zmax - zmin
    t = (z - zmin) / span if span > 0 else np.full_like(z, 0.5)
    vertices = np.stack([x * side, (t - 0.5) * 1.8 * half_height, y * side], axis=1)
    return vertices, t


def main(argv=None):
    ap = argparse.ArgumentParser(description='A plot of z = f(x, y) as a surface in the volumetric display, '
                                 'coloured by height.')
    ap.add_argument('--socket', help="spindled's socket (default: $SPINDLE_SOCKET, else /run/spindle/spindle.sock)")
    which = ap.add_mutually_exclusive_group()
    which.add_argument('--function', choices=sorted(FUNCTIONS), default='ripple', help='the function (default ripple)')
    which.add_argument('--expr', help='a numpy expression in x and y instead, e.g. "np.sin(3 * x) * y"')
    ap.add_argument('--grid', type=int, default=48, help='samples along each side (default 48)')
    ap.add_argument('--seconds', type=float, default=0, help='show it this long, then exit 0 (default: until '
                    'interrupted)')
    args = ap.parse_args(argv)
    if not 2 <= args.grid <= 1000:
        ap.error('--grid must be 2 to 1000')
    if args.expr:
        expr = compile(args.expr, '--expr', 'eval')
        f = lambda x, y: eval(expr, {'np': np, 'pi': math.pi, '__builtins__': {}}, {'x': x, 'y': y})  # noqa: E731
    else:
        f = FUNCTIONS[args.function]
    try:
        x, y, z, triangles = grid_mesh(f, args.grid)
    except Exception as e:
        print(f'surface: cannot evaluate the function: {e}', file=sys.stderr)
        return 1
    if not np.all(np.isfinite(z)):
        print('surface: the function is not finite everywhere on [-1, 1]^2', file=sys.stderr)
        return 1

    try:
        sp = spindle.connect(args.socket)
    except spindle.Error as e:
        print(f'surface: {e}', file=sys.stderr)
        return 1
    with sp:
        vertices, t = fit_surface(x, y, z, sp.device.half_height)
        surface = sp.create_list()
        if sp.version >= 2:
            surface.mesh(vertices, triangles, height_colours(t))
        else:  # version 1: no indices, no colour per vertex
            surface.set_color(0, 255, 128).triangles(vertices[triangles])
        sp.create_layer(surface)
        try:
            frame = sp.commit_and_wait()
        except spindle.Error as e:
            print(f'surface: {e}', file=sys.stderr)
            return 1
        print(f'surface: {len(triangles)} triangles shown in volume {frame.volume_seq}', flush=True)
        end = time.monotonic() + args.seconds
        try:
            while args.seconds <= 0 or time.monotonic() < end:
                left = 1.0 if args.seconds <= 0 else min(1.0, end - time.monotonic())
                sp.dispatch(timeout=max(left, 0))
        except KeyboardInterrupt:
            pass
        except spindle.Error as e:
            print(f'surface: {e}', file=sys.stderr)
            return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
