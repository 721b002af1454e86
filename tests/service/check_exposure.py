#!/usr/bin/env python3
"""Rates a service unit with `systemd-analyze security --offline=true` and
fails when its overall exposure is above the limit (docs/hardware.md,
systemd/spindled.service). Exits 77 (skipped) when systemd-analyze is not
installed or predates --offline (systemd 250).

    check_exposure.py UNIT [MAX]      MAX defaults to 2.0
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

SKIP = 77


def systemd_version(analyze):
    out = subprocess.run([analyze, '--version'], capture_output=True, text=True).stdout
    m = re.match(r'systemd (\d+)', out)
    return int(m.group(1)) if m else 0


def main():
    unit = sys.argv[1]
    limit = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    analyze = shutil.which('systemd-analyze')
    if not analyze:
        print('systemd-analyze not installed: skipped')
        return SKIP
    version = systemd_version(analyze)
    if version < 250:
        print(f'systemd-analyze {version} has no --offline: skipped')
        return SKIP
    # A directory of its own: systemd-analyze also reads drop-ins next to the
    # unit (NAME.service.d/), and the build directory must not lend it any.
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, os.path.basename(unit))
        shutil.copyfile(unit, path)
        p = subprocess.run([analyze, 'security', '--offline=true', '--no-pager', path],
                           capture_output=True, text=True)
    report = p.stdout + p.stderr
    m = re.search(r'Overall exposure level for \S+: ([0-9.]+)', report)
    if not m:
        print(report)
        print(f'no overall exposure level in the output (exit {p.returncode})')
        return 1
    exposure = float(m.group(1))
    if exposure > limit:
        print(report)
        print(f'{os.path.basename(unit)}: exposure {exposure} is above {limit}: FAILED')
        return 1
    print(f'{os.path.basename(unit)}: exposure {exposure} (at most {limit})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
