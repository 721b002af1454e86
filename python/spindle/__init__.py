"""Python binding of libspindle, the client library of the Spindle
volumetric display daemon (spindled).

A client connects, creates buffers (vertex data), display lists (retained
drawing commands), layers (a list's placement in the shared volume) and
volumes (3-D grids of samples, such as a CT scan, that lists draw), and
commits: everything set since the last commit shows together::

    import numpy as np
    import spindle

    with spindle.connect() as sp:             # $SPINDLE_SOCKET, else /run/spindle/spindle.sock
        tri = np.array([[0, 0.5, 0], [-0.5, -0.5, 0], [0.5, -0.5, 0]])
        lst = sp.create_list().set_color(255, 128, 0).triangles(tri)
        layer = sp.create_layer(lst)
        frame = sp.commit_and_wait()          # on the display from here on
        print('shown in volume', frame.volume_seq)

Coordinates are volume space: y up along the rotation axis, the display
radius is 1, and the volume is ``x**2 + z**2 <= 1``, ``abs(y) <= h``
(``sp.device.half_height``). Transforms are 4x4 numpy arrays
(:mod:`spindle.transform`). Errors raise :class:`spindle.Error` subclasses
(:mod:`spindle.errors`). docs/python.md describes it all; the C API it
wraps is libclient/include/spindle/spindle.h.

The package loads libspindle.so.0 through ctypes: ``$SPINDLE_LIBRARY`` (or
:func:`load_library`) names another, such as a build tree's.
"""
from . import transform
from ._core import (INLINE_MAX, Batch, Buffer, Connection, FrameRequest, Layer, List, Volume, connect, library_version,
                    load_library)
from .capture import Capture
from .errors import (CaptureError, CommitRefused, ConnectionLost, Error, LibraryError, NotConnected, NotSupported,
                     ProtocolError, Timeout)
from .protocol_errors import (BadFdError, InvalidMessageError, InvalidMethodError, InvalidObjectError,
                              InvalidValueError, NoMemoryError, QuotaError, RefusedBusy, RefusedDenied,
                              RefusedOutOfRange, RefusedQuota, TooManyClientsError, VersionError)
from .types import (Calibration, CalibrationKey, Composition, DeviceInfo, Frame, IndexType, Limits, Mode, Refusal,
                    Sampling, Service, State, Status, VertexFormat, VolumeType)

#: Default socket path, used when neither a path nor SPINDLE_SOCKET is given.
DEFAULT_SOCKET = '/run/spindle/spindle.sock'

__all__ = [
    'connect', 'load_library', 'library_version', 'Connection', 'Buffer', 'List', 'Layer', 'Volume', 'FrameRequest',
    'Batch', 'Capture', 'transform', 'Mode', 'VertexFormat', 'IndexType', 'Refusal', 'CalibrationKey', 'VolumeType',
    'Sampling', 'DeviceInfo', 'State',
    'Frame', 'Status', 'Limits', 'Service', 'Composition', 'Calibration', 'Error', 'LibraryError', 'NotConnected',
    'ConnectionLost', 'ProtocolError', 'CommitRefused', 'NotSupported', 'CaptureError', 'Timeout',
    'InvalidObjectError', 'InvalidMethodError', 'InvalidMessageError', 'InvalidValueError', 'BadFdError',
    'QuotaError', 'VersionError', 'NoMemoryError', 'TooManyClientsError', 'RefusedQuota', 'RefusedDenied',
    'RefusedBusy', 'RefusedOutOfRange', 'DEFAULT_SOCKET', 'INLINE_MAX'
]
