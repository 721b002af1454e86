"""libspindle through ctypes: the library's loading, its structures, callback
types and function prototypes, as libclient/include/spindle/spindle.h
declares them (tests/python/test_layout.py checks the structures' layout
against the header, compiled)."""
import ctypes
import os
import threading
from ctypes import (CFUNCTYPE, POINTER, Structure, c_bool, c_char, c_char_p, c_float, c_int, c_int32, c_size_t,
                    c_uint8, c_uint32, c_uint64, c_void_p)

from .errors import LibraryError

#: The soname loaded when neither load_library() nor $SPINDLE_LIBRARY names another.
SONAME = 'libspindle.so.0'


class DeviceInfo(Structure):
    """struct spindle_device_info"""
    _fields_ = [
        ('width', c_uint32),
        ('height', c_uint32),
        ('images_per_rev', c_uint32),
        ('mirrored', c_bool),
        ('half_height', c_float),
        ('rpm', c_float),
        ('name', c_char * 64),
    ]


class Limits(Structure):
    """struct spindle_limits"""
    _fields_ = [
        ('refused_clients', c_uint64),
        ('refused_per_user', c_uint64),
        ('refused_incomplete', c_uint64),
        ('handshake_timeouts', c_uint64),
        ('accept_pauses', c_uint64),
        ('clients_in_handshake', c_uint32),
        ('fds', c_uint32),
        ('fd_limit', c_uint32),
        ('memory_used', c_uint64),
        ('memory_budget', c_uint64),
        ('refused_memory', c_uint64),
        ('mappings', c_uint32),
        ('mapping_budget', c_uint32),
        ('refused_mappings', c_uint64),
    ]


class Service(Structure):
    """struct spindle_service"""
    _fields_ = [
        ('watchdog_ms', c_uint32),
        ('watchdog_fed', c_uint64),
        ('watchdog_withheld', c_uint64),
        ('max_client_fds', c_uint32),
        ('refused_fds', c_uint64),
    ]


class Composition(Structure):
    """struct spindle_composition"""
    _fields_ = [
        ('cache', c_bool),
        ('objects', c_uint32),
        ('cached', c_uint32),
        ('cache_bytes', c_uint64),
        ('cache_budget', c_uint64),
        ('hits', c_uint64),
        ('misses', c_uint64),
        ('creates', c_uint64),
        ('invalidations', c_uint64),
        ('evictions', c_uint64),
        ('objects_rendered', c_uint32),
        ('objects_reused', c_uint32),
        ('render_us', c_uint32),
        ('compose_us', c_uint32),
    ]


class Status(Structure):
    """struct spindle_status"""
    _fields_ = [
        ('rpm', c_float),
        ('locked', c_bool),
        ('blanked', c_bool),
        ('projector_present', c_bool),
        ('volumes_shown', c_uint64),
        ('clients', c_uint32),
        ('underruns', c_uint64),
        ('volumes_rendered', c_uint64),
        ('volumes_skipped', c_uint64),
        ('bytes_uploaded', c_uint64),
        ('render_us', c_uint32),
        ('jitter_us', c_float),
        ('missed_pulses', c_uint64),
        ('upload_rate', c_uint64),
        ('index_error_us', c_float),
        ('angle_error_p99', c_float),
        ('angle_error_max', c_float),
        ('limits_known', c_bool),
        ('limits', Limits),
        ('service', Service),
        ('composition_known', c_bool),
        ('composition', Composition),
    ]


class StatusRoom(Structure):
    """A struct spindle_status with room after it: spindle_get_status() of a
    newer library that appended fields writes into the spare bytes instead
    of past the end."""
    _fields_ = [('status', Status), ('spare', c_uint8 * 1024)]


class State(Structure):
    """struct spindle_state"""
    _fields_ = [
        ('locked', c_bool),
        ('blanked', c_bool),
        ('projector_present', c_bool),
        ('rpm', c_float),
    ]


class Frame(Structure):
    """struct spindle_frame"""
    _fields_ = [('volume_seq', c_uint64), ('time_ns', c_uint64)]


class Calibration(Structure):
    """struct spindle_calibration"""
    _fields_ = [
        ('phase_offset', c_float),
        ('axis_offset_u', c_int32),
        ('axis_offset_v', c_int32),
        ('vertical_scale', c_float),
        ('vertical_offset', c_float),
    ]


STATE_FUNC = CFUNCTYPE(None, c_void_p, POINTER(State))
REFUSED_FUNC = CFUNCTYPE(None, c_void_p, c_int, c_uint32, c_char_p)
LOG_FUNC = CFUNCTYPE(None, c_void_p, c_char_p)
FRAME_FUNC = CFUNCTYPE(None, c_void_p, POINTER(Frame))


class Listener(Structure):
    """struct spindle_listener"""
    _fields_ = [('state', STATE_FUNC), ('refused', REFUSED_FUNC)]


# Handles are opaque pointers: c_void_p (a Python int, or None for NULL).
_h = c_void_p
_m16 = POINTER(c_float)

# name: (restype, argtypes), every function of libspindle.syms.
PROTOTYPES = {
    'spindle_connect': (_h, [c_char_p]),
    'spindle_connect_version': (_h, [c_char_p, c_uint32]),
    'spindle_disconnect': (None, [_h]),
    'spindle_set_log_handler': (None, [_h, LOG_FUNC, c_void_p]),
    'spindle_get_version': (c_uint32, [_h]),
    'spindle_set_listener': (None, [_h, POINTER(Listener), c_void_p]),
    'spindle_get_state': (c_int, [_h, POINTER(State)]),
    'spindle_get_device_info': (POINTER(DeviceInfo), [_h]),
    'spindle_get_fd': (c_int, [_h]),
    'spindle_dispatch': (c_int, [_h]),
    'spindle_flush': (c_int, [_h]),
    'spindle_roundtrip': (c_int, [_h]),
    'spindle_get_error': (c_char_p, [_h]),
    'spindle_get_error_code': (c_uint32, [_h]),
    'spindle_library_version': (c_char_p, []),
    'spindle_buffer_create': (_h, [_h, c_void_p, c_size_t]),
    'spindle_buffer_create_inline': (_h, [_h, c_void_p, c_size_t]),
    'spindle_buffer_create_from_fd': (_h, [_h, c_int, c_uint64]),
    'spindle_buffer_destroy': (None, [_h]),
    'spindle_list_create': (_h, [_h]),
    'spindle_list_destroy': (None, [_h]),
    'spindle_list_clear': (c_int, [_h]),
    'spindle_list_set_color': (c_int, [_h, c_uint8, c_uint8, c_uint8, c_uint8]),
    'spindle_list_set_transform': (c_int, [_h, _m16]),
    'spindle_list_points': (c_int, [_h, _h, c_size_t, c_uint32, c_uint32]),
    'spindle_list_lines': (c_int, [_h, _h, c_size_t, c_uint32, c_uint32]),
    'spindle_list_triangles': (c_int, [_h, _h, c_size_t, c_uint32, c_uint32]),
    'spindle_list_draw': (c_int, [_h, c_int, _h, c_size_t, c_uint32, c_uint32]),
    'spindle_list_draw_indexed': (c_int, [_h, c_int, _h, c_size_t, c_uint32, c_uint32, _h, c_size_t, c_uint32, c_int]),
    'spindle_list_set_vertex_format': (c_int, [_h, c_int]),
    'spindle_list_set_point_size': (c_int, [_h, c_uint32]),
    'spindle_list_push': (c_int, [_h]),
    'spindle_list_pop': (c_int, [_h]),
    'spindle_list_multiply_transform': (c_int, [_h, _m16]),
    'spindle_layer_create': (_h, [_h]),
    'spindle_layer_destroy': (None, [_h]),
    'spindle_layer_set_list': (c_int, [_h, _h]),
    'spindle_layer_set_transform': (c_int, [_h, _m16]),
    'spindle_layer_set_visible': (c_int, [_h, c_bool]),
    'spindle_layer_set_priority': (c_int, [_h, c_int32]),
    'spindle_layer_set_exclusive': (c_int, [_h, c_bool]),
    'spindle_request_frame': (c_int, [_h, FRAME_FUNC, c_void_p]),
    'spindle_commit': (c_int, [_h]),
    'spindle_commit_and_wait': (c_int, [_h, POINTER(Frame)]),
    'spindle_get_status': (c_int, [_h, POINTER(Status)]),
    'spindle_capture': (c_int, [_h, POINTER(c_int), POINTER(c_size_t)]),
    'spindle_get_calibration': (c_int, [_h, POINTER(Calibration)]),
    'spindle_calibrate': (c_int, [_h, c_int, c_float, POINTER(Calibration)]),
    'spindle_volume_create': (_h, [_h, _h, c_uint64, c_int, POINTER(c_uint32), POINTER(c_float)]),
    'spindle_volume_destroy': (None, [_h]),
    'spindle_list_draw_volume': (c_int, [_h, _h, c_int, c_float, c_float, c_float]),
    'spindle_list_set_volume_lut': (c_int, [_h, _h, c_uint64, c_uint32]),
}

# Added after SPINDLE_0.1: a library without them still loads.
OPTIONAL = {
    'spindle_library_version', 'spindle_get_calibration', 'spindle_calibrate', 'spindle_volume_create',
    'spindle_volume_destroy', 'spindle_list_draw_volume', 'spindle_list_set_volume_lut'
}

_lock = threading.Lock()
_lib = None
_lib_path = None


def _resolve(path):
    if os.path.isdir(path):
        return os.path.join(path, SONAME)
    return path


def load(path=None):
    """Loads libspindle once: path, else $SPINDLE_LIBRARY, else the soname
    libspindle.so.0 (the dynamic linker's search path). A folder stands for
    libspindle.so.0 in it. Returns the ctypes library; raises LibraryError."""
    global _lib, _lib_path
    with _lock:
        if _lib is not None:
            if path is not None and _resolve(path) != _lib_path:
                raise LibraryError(f'libspindle is already loaded from {_lib_path}: load_library({path!r}) '
                                   'must come before the first connection')
            return _lib
        want = _resolve(path or os.environ.get('SPINDLE_LIBRARY') or SONAME)
        try:
            lib = ctypes.CDLL(want, use_errno=True)
        except OSError as e:
            raise LibraryError(f'cannot load libspindle ({want}): {e}; install libspindle, or set SPINDLE_LIBRARY '
                               'to the path of libspindle.so.0') from None
        for name, (restype, argtypes) in PROTOTYPES.items():
            try:
                f = getattr(lib, name)
            except AttributeError:
                if name in OPTIONAL:
                    continue
                raise LibraryError(f'{want} has no {name}: not libspindle, or too old') from None
            f.restype = restype
            f.argtypes = argtypes
        _lib, _lib_path = lib, want
        return lib


def loaded_path():
    """Where libspindle was loaded from (None before it is)."""
    return _lib_path
