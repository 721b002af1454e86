"""The exceptions of the spindle package.

Every exception the binding raises for the display's sake derives from
:class:`Error`. Wrong arguments (an array of the wrong shape, a colour out of
range) raise the built-in :class:`TypeError` or :class:`ValueError` before
anything is sent.

::

    Error
    +-- LibraryError          libspindle could not be loaded
    +-- NotConnected          no connection: connecting failed, or it was closed
    +-- ConnectionLost        the connection broke (spindled closed it, or was killed)
    |   +-- ProtocolError     spindled ended it with a fatal error (display.error)
    |       +-- InvalidObjectError, InvalidMethodError, InvalidMessageError,
    |           InvalidValueError, BadFdError, QuotaError, VersionError,
    |           NoMemoryError, TooManyClientsError   (spindle.protocol_errors)
    +-- CommitRefused         spindled refused a commit; the connection goes on
    |   +-- RefusedQuota, RefusedDenied, RefusedBusy  (spindle.protocol_errors)
    +-- NotSupported          the request needs a newer protocol version
    +-- CaptureError          a capture was denied or failed
    +-- Timeout               a wait ran out of time

The per-code classes are generated from proto/spindle.xml into
:mod:`spindle.protocol_errors` (python/gen_errors.py).
"""
import errno as _errno
import os as _os

__all__ = [
    'Error', 'LibraryError', 'NotConnected', 'ConnectionLost', 'ProtocolError', 'CommitRefused', 'NotSupported',
    'CaptureError', 'Timeout'
]


class Error(Exception):
    """Base class of the package's exceptions.

    ``message`` is the explanation (for a broken connection, the text of
    ``spindle_get_error()``); ``errno`` the C library's error number where one
    was returned, else None.
    """

    def __init__(self, message, errno=None):
        super().__init__(message)
        self.message = message
        self.errno = errno

    @classmethod
    def from_errno(cls, err, what):
        """An instance for a negative (or positive) errno returned by a libspindle call named ``what``."""
        err = abs(err)
        return cls(f'{what}: {_os.strerror(err)}', err)


class LibraryError(Error):
    """libspindle (libspindle.so.0) could not be loaded, or lacks a function
    the binding needs. Set ``SPINDLE_LIBRARY`` to the library's path, or call
    :func:`spindle.load_library` with it before connecting."""


class NotConnected(Error):
    """There is no connection: connecting to spindled failed (no daemon at
    the socket, permission denied, no common protocol version, too many
    clients), or the :class:`~spindle.Connection` (or the object used) was
    closed or destroyed."""


class ConnectionLost(Error):
    """The connection to spindled broke: the daemon closed it or went away.
    Every later call on the connection raises it again; ``message`` is
    ``spindle_get_error()``'s explanation. Close the connection and connect
    again."""

    def __init__(self, message, errno=_errno.EPIPE):
        super().__init__(message, errno)


class ProtocolError(ConnectionLost):
    """spindled ended the connection with a fatal protocol error
    (display.error, docs/protocol.md). ``code`` is the error's number (enum
    spindle_error_code), ``name`` its name in proto/spindle.xml. Subclasses
    name each code; an unknown (newer) code raises this class itself."""
    code = 0
    name = 'unknown'

    def __init__(self, message, code=None):
        super().__init__(message)
        if code is not None:
            self.code = code


class CommitRefused(Error):
    """spindled refused a commit (display.refused, protocol version 2):
    nothing of it shows, and every change stays pending (frame requests
    too); the connection goes on. ``code`` is the refusal's number (enum
    spindle_refusal), ``name`` its name in proto/spindle.xml."""
    code = 0
    name = 'unknown'

    def __init__(self, message, errno=None, code=None):
        super().__init__(message, errno)
        if code is not None:
            self.code = code


class NotSupported(Error):
    """The request needs a newer protocol version than the connection's
    (:attr:`spindle.Connection.version`): ENOTSUP (version 2 at 1), or
    EPROTONOSUPPORT (calibration and volumes, version 6, before it or with a
    libspindle that predates them)."""

    def __init__(self, message, errno=_errno.ENOTSUP):
        super().__init__(message, errno)


class CaptureError(Error):
    """A capture failed: ``errno`` is EACCES when the daemon's policy denies
    this client captures (only root, the daemon's own user and its admin
    group may capture), EIO when the daemon could not make one."""


class Timeout(Error):
    """A wait ran out of time before what it waited for happened (the
    connection is still usable)."""

    def __init__(self, message, errno=_errno.ETIMEDOUT):
        super().__init__(message, errno)
