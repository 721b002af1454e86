#!/usr/bin/env python3
"""Runs the Python binding's pytest suite (tests/python) with the
interpreter meson found, or skips (exit 77) where numpy or pytest is
missing, or where the sanitizer runtime cannot be preloaded.

    run.py TESTS_DIR [--skip REASON] [PYTEST ARGS...]
"""
import sys


def main():
    tests = sys.argv[1]
    args = sys.argv[2:]
    if args[:1] == ['--skip']:
        print('SKIP:', args[1])
        return 77
    try:
        import numpy  # noqa: F401
        import pytest
    except ImportError as e:
        print(f'SKIP: {e.name} is missing for {sys.executable} (scripts/install-deps installs python3-numpy and '
              'python3-pytest)')
        return 77
    return pytest.main(['-q', '-p', 'no:cacheprovider', '-o', 'console_output_style=classic', '-rs', tests, *args])


if __name__ == '__main__':
    sys.exit(main())
