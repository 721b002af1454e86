"""The display's calibration (protocol version 6) through the binding:
Connection.calibration() and Connection.calibrate() by config name and by
CalibrationKey, refusals (out of range, a non-integer offset) that change
nothing and leave the connection, and a pending frame request, as they
were, arguments checked before sending, and NotSupported at version 5."""
import errno

import pytest

import spindle
from spindle import CalibrationKey

IDENTITY = spindle.Calibration(phase_offset=0.0, axis_offset_u=0, axis_offset_v=0, vertical_scale=1.0,
                               vertical_offset=0.0)


def test_fresh_daemon_is_the_identity(sp):
    cal = sp.calibration()
    assert isinstance(cal, spindle.Calibration) and cal == IDENTITY
    assert isinstance(cal.axis_offset_u, int) and isinstance(cal.vertical_scale, float)


def test_calibrate_by_name_and_by_key(sp, daemon):
    cal = sp.calibrate('axis-offset-u', -3)
    assert cal == spindle.Calibration(0.0, -3, 0, 1.0, 0.0)
    assert sp.calibration().axis_offset_u == -3
    assert sp.calibrate(CalibrationKey.VERTICAL_SCALE, 1.5).vertical_scale == 1.5
    assert sp.calibrate(CalibrationKey.AXIS_OFFSET_V, 2.0).axis_offset_v == 2  # a whole float is whole pixels
    assert sp.calibrate(0, -12.5).phase_offset == -12.5  # the key's number
    assert sp.calibrate('axis-offset-u', 32).axis_offset_u == 32  # a quarter of the 128 columns
    assert sp.calibrate('vertical-offset', -0.25).vertical_offset == -0.25
    want = spindle.Calibration(-12.5, 32, 2, 1.5, -0.25)
    assert sp.calibration() == want
    # It is the display's: another client sees it.
    with spindle.connect(daemon.sock) as other:
        assert other.calibration() == want
    assert [k.config_name for k in CalibrationKey] == ['phase-offset', 'axis-offset-u', 'axis-offset-v',
                                                       'vertical-scale', 'vertical-offset']
    assert CalibrationKey('vertical-scale') is CalibrationKey.VERTICAL_SCALE


@pytest.mark.parametrize('key, value', [('axis-offset-u', 1000), ('axis-offset-u', 33), ('axis-offset-v', -33),
                                        ('vertical-scale', 3), ('vertical-scale', 0.25), ('phase-offset', 180.5),
                                        ('vertical-offset', 0.75),
                                        ('axis-offset-u', 2.5), ('axis-offset-v', float('nan'))])
def test_out_of_range_is_refused_and_changes_nothing(sp, key, value):
    refusals = []
    sp.on_refused = lambda code, obj, message: refusals.append((code, obj, message))
    before = sp.calibrate('axis-offset-u', -3)
    with pytest.raises(spindle.RefusedOutOfRange) as e:
        sp.calibrate(key, value)
    err = e.value
    assert isinstance(err, spindle.CommitRefused) and err.code == 4 and err.name == 'out_of_range'
    assert err.errno == errno.ERANGE and 'out of range' in err.message and key in err.message
    assert refusals == [(spindle.Refusal.OUT_OF_RANGE, 1, refusals[0][2])]
    assert sp.calibration() == before
    sp.roundtrip()
    assert sp.error is None


def test_refused_calibration_is_not_a_refused_commit(sp):
    """A frame request pending while a calibration is refused still fires with its commit."""
    sp.create_layer(sp.create_list().points([0, 0, 0]))
    req = sp.request_frame()
    sp.commit()
    with pytest.raises(spindle.RefusedOutOfRange):
        sp.calibrate('vertical-scale', 3)
    assert req.wait(timeout=10).volume_seq > 0
    assert sp.commit_and_wait().volume_seq > 0


def test_arguments_are_checked_before_sending(sp):
    for key in ('axis_offset_u', 'AXIS_OFFSET_U', 'nope', 5, -1, None):
        with pytest.raises(ValueError, match='not a calibration key'):
            sp.calibrate(key, 1)
    for value in ('1', None, True, [1]):
        with pytest.raises(TypeError):
            sp.calibrate('axis-offset-u', value)
    # Nothing reached the daemon (an unknown key would be a fatal error).
    sp.roundtrip()
    assert sp.error is None and sp.calibration() == IDENTITY


def test_not_supported_before_version_6(daemon):
    with spindle.connect(daemon.sock, version=5) as old:
        assert old.version == 5
        with pytest.raises(spindle.NotSupported) as e:
            old.calibration()
        assert e.value.errno == errno.EPROTONOSUPPORT
        with pytest.raises(spindle.NotSupported):
            old.calibrate('axis-offset-u', 1)
        old.roundtrip()
        assert old.error is None
