"""The binding's ctypes structures (python/spindle/_lib.py) have the layout
the C compiler gives spindle.h's: tests/python/layout.c, built against the
header, prints every structure's size and every field's offset and size.
And every function libclient/libspindle.syms exports is bound (or listed as
not bound yet)."""
import ctypes
import os
import re
import subprocess

import spindle
from spindle import _lib

STRUCTS = {
    'spindle_device_info': _lib.DeviceInfo,
    'spindle_limits': _lib.Limits,
    'spindle_service': _lib.Service,
    'spindle_composition': _lib.Composition,
    'spindle_status': _lib.Status,
    'spindle_state': _lib.State,
    'spindle_frame': _lib.Frame,
    'spindle_listener': _lib.Listener,
    'spindle_calibration': _lib.Calibration,
}


def c_layout():
    """{'NAME size': (SIZE,), 'NAME.FIELD': (OFFSET, SIZE), 'CONSTANT': (VALUE,)} from layout.c."""
    out = subprocess.run([os.environ['SPINDLE_LAYOUT']], capture_output=True, text=True, check=True).stdout
    layout = {}
    for line in out.splitlines():
        name, *values = line.split()
        if values[0] == 'size':
            layout[name + ' size'] = (int(values[1]), )
        else:
            layout[name] = tuple(int(v) for v in values)
    return layout


def test_structures_match_the_header():
    c = c_layout()
    mismatches = []
    seen = set()
    for name, cls in STRUCTS.items():
        if c.get(name + ' size') != (ctypes.sizeof(cls), ):
            mismatches.append(f'{name}: C size {c.get(name + " size")}, ctypes {ctypes.sizeof(cls)}')
        for field, _ in cls._fields_:
            key = f'{name}.{field}'
            seen.add(key)
            f = getattr(cls, field)
            if c.get(key) != (f.offset, f.size):
                mismatches.append(f'{key}: C (offset, size) {c.get(key)}, ctypes {(f.offset, f.size)}')
    missing = [k for k in c if '.' in k and k.split('.')[0] in STRUCTS and k not in seen]
    assert not mismatches and not missing, '\n'.join(mismatches + [f'{k}: not in the binding' for k in missing])


def test_constants_match_the_header():
    c = c_layout()
    assert c['enum.size'] == (ctypes.sizeof(ctypes.c_int), )
    assert c['SPINDLE_INLINE_MAX'] == (spindle.INLINE_MAX, )
    assert c['enum.volume_type.size'] == c['enum.sampling.size'] == (ctypes.sizeof(ctypes.c_int), )
    for t in spindle.VolumeType:
        assert c[f'SPINDLE_VOLUME_{t.name}'] == (t.value, ), t
    for s in spindle.Sampling:
        assert c[f'SPINDLE_{s.name}'] == (s.value, ), s


# Exported by libspindle but not (yet) bound: the protocol 5 watchers.
NOT_BOUND = {
    'spindle_get_watch_stats', 'spindle_watch_create', 'spindle_watch_destroy', 'spindle_watch_get_error',
    'spindle_watch_release'
}


def test_every_exported_function_is_bound():
    syms = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'libclient', 'libspindle.syms')
    with open(syms) as f:
        exported = set(re.findall(r'^\s*(spindle_\w+);', f.read(), flags=re.M))
    bound = set(_lib.PROTOTYPES)
    assert not bound - exported, f'bound but not exported: {sorted(bound - exported)}'
    new = exported - bound - NOT_BOUND
    assert not new, (f'libspindle exports {sorted(new)}: bind them in python/spindle/_lib.py (PROTOTYPES) and '
                     '_core.py or _objects.py, or list them in NOT_BOUND here')
