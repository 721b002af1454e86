"""The value types of the spindle package: enums mirroring spindle.h's and
frozen dataclasses for what the daemon reports (device info, status, state,
frames, calibration)."""
import dataclasses
import enum
from typing import Optional

__all__ = [
    'Mode', 'VertexFormat', 'IndexType', 'Refusal', 'CalibrationKey', 'VolumeType', 'Sampling', 'DeviceInfo', 'State',
    'Frame', 'Limits', 'Service', 'Composition', 'Status', 'Calibration'
]


class Mode(enum.IntEnum):
    """Primitive modes of draws (enum spindle_mode)."""
    POINTS = 0  #: each vertex a point
    LINES = 1  #: vertices 2i, 2i+1 a segment
    TRIANGLES = 2  #: vertices 3i .. 3i+2 a triangle
    LINE_STRIP = 3  #: vertices i, i+1 joined, for every i (protocol version 2)


class VertexFormat(enum.IntEnum):
    """Vertex layouts (enum spindle_vertex_format, protocol version 2)."""
    XYZ = 0  #: 3 float32: 12 bytes
    XYZ_RGBA8 = 1  #: 3 float32, then R, G, B, A bytes: 16 bytes
    XYZ_RGBA_FLOAT = 2  #: 3 float32, then 4 float32 in 0..1: 28 bytes

    @property
    def size(self):
        """Bytes per vertex."""
        return (12, 16, 28)[self]


class IndexType(enum.IntEnum):
    """Index sizes of indexed draws (enum spindle_index_type): the value is bytes per index."""
    U16 = 2  #: uint16 indices
    U32 = 4  #: uint32 indices


class Refusal(enum.IntEnum):
    """Why the daemon refused a commit, or a calibration (enum spindle_refusal)."""
    QUOTA = 1  #: more primitives than this client's quota
    DENIED = 2  #: exclusive layer, or calibration, not allowed by policy
    BUSY = 3  #: another client's exclusive layer shows
    OUT_OF_RANGE = 4  #: a calibration value out of its range (protocol version 6)


class CalibrationKey(enum.IntEnum):
    """The calibration values (enum spindle_calibration_key, protocol
    version 6). ``CalibrationKey('axis-offset-u')`` takes the config name
    too (spindled(8), ``spindlectl calibrate``)."""
    PHASE_OFFSET = 0  #: degrees, -180 to 180
    AXIS_OFFSET_U = 1  #: whole pixels, at most a quarter of the image width either way
    AXIS_OFFSET_V = 2  #: whole pixels, at most a quarter of the image height either way
    VERTICAL_SCALE = 3  #: a factor, 0.5 to 2
    VERTICAL_OFFSET = 4  #: volume units, -0.5 to 0.5

    @property
    def config_name(self):
        """The key's name in spindled's config file: 'phase-offset', 'axis-offset-u', ..."""
        return self.name.lower().replace('_', '-')

    @classmethod
    def _missing_(cls, value):
        for key in cls:
            if value == key.config_name:
                return key
        return None


class VolumeType(enum.IntEnum):
    """Sample types of volumes (enum spindle_volume_type, protocol version
    6): :meth:`spindle.Connection.volume` picks it from the array's dtype."""
    U8 = 1  #: uint8
    U16 = 2  #: uint16
    I16 = 3  #: int16 (Hounsfield units of a CT, for one)
    F32 = 4  #: float32 (NaN is dark)
    RGBA8 = 5  #: 4 uint8 per sample, each its own colour, alpha scaling it

    @property
    def size(self):
        """Bytes per sample."""
        return (1, 2, 2, 4, 4)[self - 1]


class Sampling(enum.IntEnum):
    """How :meth:`spindle.List.draw_volume` reads a volume between its
    samples (enum spindle_sampling, protocol version 6).
    ``Sampling('trilinear')`` takes the lower-case name too."""
    NEAREST = 0  #: the nearest sample: blocks, one per sample
    TRILINEAR = 1  #: the 8 samples around, weighted: smooth

    @classmethod
    def _missing_(cls, value):
        if isinstance(value, str):
            for s in cls:
                if value == s.name.lower():
                    return s
        return None


def _from_struct(cls, s, **override):
    values = {f.name: getattr(s, f.name) for f in dataclasses.fields(cls) if f.name not in override}
    values.update(override)
    return cls(**values)


@dataclasses.dataclass(frozen=True)
class DeviceInfo:
    """The display device, as the daemon reports it at connection
    (struct spindle_device_info).

    Volume space: y up along the rotation axis, unit the display's radius;
    what can be shown is ``x**2 + z**2 <= 1``, ``abs(y) <= half_height``.

    Attributes: ``width`` (pixels per image row), ``height`` (rows per
    image), ``images_per_rev`` (images shown per revolution, N),
    ``mirrored`` (volumes hold N/2 images), ``half_height`` (h),
    ``rpm`` (nominal rotor speed), ``name`` (device description).
    """
    width: int
    height: int
    images_per_rev: int
    mirrored: bool
    half_height: float
    rpm: float
    name: str

    @property
    def images_per_volume(self):
        """Images a volume holds: N/2 when mirrored, else N."""
        return self.images_per_rev // 2 if self.mirrored else self.images_per_rev

    @classmethod
    def _from_c(cls, d):
        return _from_struct(cls, d, name=d.name.decode('utf-8', 'replace'))


@dataclasses.dataclass(frozen=True)
class State:
    """The display's state, pushed by the daemon when it changes
    (struct spindle_state, protocol version 2): ``locked`` (the sync is
    locked to the rotor), ``blanked`` (the projector is dark),
    ``projector_present``, ``rpm`` (measured, 0 when not turning)."""
    locked: bool
    blanked: bool
    projector_present: bool
    rpm: float

    @classmethod
    def _from_c(cls, s):
        return _from_struct(cls, s)


@dataclasses.dataclass(frozen=True)
class Frame:
    """When a committed state was first shown (struct spindle_frame):
    ``volume_seq``, the sequence number of the volume showing it, and
    ``time_ns``, the CLOCK_MONOTONIC time (ns, :func:`time.clock_gettime_ns`
    with :data:`time.CLOCK_MONOTONIC`) of the revolution start it is shown
    from."""
    volume_seq: int
    time_ns: int

    @classmethod
    def _from_c(cls, f):
        return _from_struct(cls, f)


@dataclasses.dataclass(frozen=True)
class Limits:
    """The daemon's limits and what they did since it started (struct
    spindle_limits; docs/man/spindled.8): refused connections
    (``refused_clients`` over max-clients, ``refused_per_user``,
    ``refused_incomplete``), ``handshake_timeouts``, ``accept_pauses``,
    ``clients_in_handshake``, the daemon's open ``fds`` and ``fd_limit``,
    ``memory_used`` and ``memory_budget`` (bytes), ``refused_memory``,
    memfd ``mappings`` and ``mapping_budget``, ``refused_mappings``."""
    refused_clients: int
    refused_per_user: int
    refused_incomplete: int
    handshake_timeouts: int
    accept_pauses: int
    clients_in_handshake: int
    fds: int
    fd_limit: int
    memory_used: int
    memory_budget: int
    refused_memory: int
    mappings: int
    mapping_budget: int
    refused_mappings: int


@dataclasses.dataclass(frozen=True)
class Service:
    """The daemon's safeguards as a service (struct spindle_service):
    ``watchdog_ms`` (systemd's WatchdogSec, 0: none), ``watchdog_fed``,
    ``watchdog_withheld``, ``max_client_fds``, ``refused_fds``."""
    watchdog_ms: int
    watchdog_fed: int
    watchdog_withheld: int
    max_client_fds: int
    refused_fds: int


@dataclasses.dataclass(frozen=True)
class Composition:
    """What the object cache and compositor did (struct spindle_composition):
    ``cache`` (on), ``objects`` (layers followed), ``cached``,
    ``cache_bytes``, ``cache_budget``, ``hits``, ``misses``, ``creates``,
    ``invalidations``, ``evictions`` (over all volumes), and for the last
    volume ``objects_rendered``, ``objects_reused``, ``render_us``,
    ``compose_us``."""
    cache: bool
    objects: int
    cached: int
    cache_bytes: int
    cache_budget: int
    hits: int
    misses: int
    creates: int
    invalidations: int
    evictions: int
    objects_rendered: int
    objects_reused: int
    render_us: int
    compose_us: int


@dataclasses.dataclass(frozen=True)
class Status:
    """The daemon's and the device's state (struct spindle_status;
    :meth:`spindle.Connection.status`). Counters count from the daemon's
    start.

    ``rpm`` (measured, 0 when not turning), ``locked``, ``blanked``,
    ``projector_present``, ``volumes_shown``, ``clients`` (this one
    included), ``underruns``, ``volumes_rendered``, ``volumes_skipped``
    (scenes identical to the last rendered), ``bytes_uploaded``,
    ``render_us`` (the last render), ``jitter_us``, ``missed_pulses``,
    ``upload_rate`` (bytes/s), ``index_error_us``, ``angle_error_p99`` and
    ``angle_error_max`` (slices; < 0: unknown). ``limits`` (:class:`Limits`,
    protocol version 3), ``service`` (:class:`Service`) and ``composition``
    (:class:`Composition`, both protocol version 4) are None from a daemon
    that does not report them.
    """
    rpm: float
    locked: bool
    blanked: bool
    projector_present: bool
    volumes_shown: int
    clients: int
    underruns: int
    volumes_rendered: int
    volumes_skipped: int
    bytes_uploaded: int
    render_us: int
    jitter_us: float
    missed_pulses: int
    upload_rate: int
    index_error_us: float
    angle_error_p99: float
    angle_error_max: float
    limits: Optional[Limits]
    service: Optional[Service]
    composition: Optional[Composition]

    @classmethod
    def _from_c(cls, s):
        return _from_struct(
            cls,
            s,
            limits=_from_struct(Limits, s.limits) if s.limits_known else None,
            service=_from_struct(Service, s.service) if s.composition_known else None,
            composition=_from_struct(Composition, s.composition) if s.composition_known else None)


@dataclasses.dataclass(frozen=True)
class Calibration:
    """The display's calibration (struct spindle_calibration, protocol
    version 6; :meth:`spindle.Connection.calibration`): where a real
    projector's images land against volume space. ``phase_offset``
    (degrees), ``axis_offset_u`` and ``axis_offset_v`` (whole pixels),
    ``vertical_scale`` (a factor) and ``vertical_offset`` (volume units):
    heights are drawn at ``vertical_scale * y + vertical_offset``. The
    identity is 0, 0, 0, 1.0, 0.0."""
    phase_offset: float
    axis_offset_u: int
    axis_offset_v: int
    vertical_scale: float
    vertical_offset: float

    @classmethod
    def _from_c(cls, c):
        return _from_struct(cls, c)
