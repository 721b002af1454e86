#!/usr/bin/env python3
"""display.state (version 2): sent after device at welcome, then on every
change of a flag or of the measured speed by 1% of nominal; never to a
version 1 client. The simulated rotor stalls (sim-faults stall=) and spins
up again: locked and blanked change, and the rpm with them."""
import time

from harness import Daemon, case, check, run, with_daemon, w

LOCKED, BLANKED, PRESENT = w.STATUS['locked'], w.STATUS['blanked'], w.STATUS['projector_present']


def states(c):
    return [e for e in c.log if e.name == 'display.state']


def wait_flags(c, want, mask, timeout):
    """Pumps until the last state has flags & mask == want."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        st = states(c)
        if st and st[-1]['flags'] & mask == want:
            return st[-1]
        c.pump(0.05)
    raise AssertionError(f'no state with flags & {mask} == {want} within {timeout} s: {states(c)[-6:]}')


@with_daemon('sim-faults=stall=2/0+1.5/0.5')
def state_on_stall(d):
    """Locked, then a dead stop at 2 s (unlocked, blanked, rpm 0), spin-up
    1.5 s later (locked and lit again)."""
    v2 = d.conn(2)
    v1 = d.conn(1)
    nominal = v2.device['rpm']
    first = states(v2)
    check(len(first) == 1 and v2.log[2] is first[0], f'state right after device: {v2.log}')
    st = v2.status()
    check(first[0]['flags'] & PRESENT == st['flags'] & PRESENT, f'state {first[0]} vs status {st}')
    wait_flags(v2, LOCKED, LOCKED | BLANKED, 6)
    stopped = wait_flags(v2, BLANKED, LOCKED | BLANKED, 6)
    check(stopped['rpm'] < nominal * 0.5, f'the rpm falls with the stall: {stopped}')
    lit = wait_flags(v2, LOCKED, LOCKED | BLANKED, 10)
    check(abs(lit['rpm'] - nominal) < nominal * 0.05, f'relit near the nominal speed: {lit}')
    seq = states(v2)
    for a, b in zip(seq, seq[1:]):
        check(a['flags'] != b['flags'] or abs(a['rpm'] - b['rpm']) >= 0.01 * nominal * 0.999,
              f'a state event without a change: {a} -> {b}')
    v1.pump(0.1)   # spindlewire fails on any event newer than version 1
    v1.sync()
    check(not states(v1), 'no state event at version 1')
    check(not v1.errors() and not v2.errors(), f'{v1.errors()} {v2.errors()}')
    print(f'  {len(seq)} state events: ' + ', '.join(f"{s['flags']}/{s['rpm']:.0f}" for s in seq[:12]))
    v1.close()
    v2.close()


@with_daemon()
def state_steady(d):
    """A turning, locked rotor: after lock, no state event without a change
    (the measured speed stays within 1%)."""
    c = d.conn(2)
    wait_flags(c, LOCKED, LOCKED | BLANKED, 6)
    n = len(states(c))
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        c.pump(0.1)
    check(len(states(c)) - n <= 1, f'steady rotor: {states(c)[n - 1:]}')
    c.close()


def frame_times(d, frames=40):
    """A layer moved at every frame, committed as soon as the last frame
    is done: the frames' presentation times, and the revolution period."""
    c = d.conn()
    dev = next(e for e in c.log if e.name == 'display.device')
    period = 60e9 / dev['rpm']
    buf = c.buffer(w.vertices([(-0.3, -0.3, 0.1), (0.3, 0.3, 0.1)]))
    lst, layer = c.create('create_list'), c.create('create_layer')
    c.req(lst, 'list.draw', w.MODE['lines'], buf, 0, 2, 0)
    c.req(layer, 'layer.set_list', lst)
    times = []
    for f in range(frames):
        y = 0.01 * (f % 50)
        c.req(layer, 'layer.set_transform', [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, y, 0, 1])
        times.append(c.frame_commit()['time_ns'])
    c.close()
    return times, period


def halves(times, period):
    """Each gap between presentation times in half revolutions (they all
    fall on boundaries of the simulated rotor, to its timing precision)."""
    gaps = [(b - a) / (period / 2) for a, b in zip(times, times[1:])]
    check(all(abs(g - round(g)) < 0.05 for g in gaps), f'gaps in half revolutions: {gaps}')
    return [round(g) for g in gaps]


@case
def half_turn_frames():
    """The simulated projector (protocol 1.2, mirrored) takes a new volume
    at every half-turn start: frames are shown from the middle of a
    revolution too. With half-turn-swaps = false, only from revolution
    starts."""
    for setting, want_odd in (('half-turn-swaps=true', True), ('half-turn-swaps=false', False)):
        d = Daemon(setting)
        try:
            times, period = frame_times(d)
        finally:
            d.stop()
        gaps = halves(times, period)
        odd = sum(g % 2 for g in gaps)
        check(odd > 0 if want_odd else odd == 0, f'{setting}: gaps in half revolutions {gaps}')
        print(f'  {setting}: {len(times)} frames over {(times[-1] - times[0]) / period:.1f} revolutions, '
              f'{odd} of {len(gaps)} gaps an odd number of half turns')


if __name__ == '__main__':
    run()
