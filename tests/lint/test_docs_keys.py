#!/usr/bin/env python3
"""The documents list what the code takes: every config key of
daemon/config.c (and common/calibration.c's) is described in docs/man/spindled.8 (CONFIGURATION KEYS)
and named in README.md (the --set row), and nothing else is; every long
option of daemon/main.c is in the man page's OPTIONS and the README's
table; and the man pages render without warnings (man --warnings, where
man-db is installed).

    test_docs_keys.py SOURCE_ROOT
"""
import os
import re
import shutil
import subprocess
import sys

root = sys.argv[1]
failures = []


def read(rel):
    with open(os.path.join(root, rel), encoding='utf-8') as f:
        return f.read()


def check(cond, what):
    print(('ok: ' if cond else 'FAIL: ') + what)
    if not cond:
        failures.append(what)


def man_section(text, name):
    m = re.search(r'^\.SH ' + name + r'\n(.*?)(?=^\.SH )', text, flags=re.S | re.M)
    return m.group(1) if m else ''


def man_tagged(section):
    """The names in each .TP paragraph's tag line (.B/.BR/.BI), without
    the quoted separators and values after '='."""
    names = set()
    for tag in re.findall(r'^\.TP\n(\.B[RI]? .*)$', section, flags=re.M):
        words = re.sub(r'"[^"]*"', ' ', tag.split(None, 1)[1]).split()
        for w in words:
            if re.fullmatch(r'[a-z][a-z0-9-]*', w):
                names.add(w)
            if '=' in tag:
                break  # "cache = true | false": values follow
    return names


config_c, main_c = read('daemon/config.c'), read('daemon/main.c')
man8, readme = read('docs/man/spindled.8'), read('README.md')

keys = set(re.findall(r'strcmp\(key, "([a-z0-9-]+)"\)', config_c))
# The calibration keys (config_set() looks them up in common/calibration.c).
keys |= set(re.findall(r'\[CALIBRATION_\w+\] = "([a-z0-9-]+)"', read('common/calibration.c')))
check(len(keys) > 20, f'{len(keys)} keys found in daemon/config.c')
man_keys = man_tagged(man_section(man8, 'CONFIGURATION KEYS'))
check(keys == man_keys, 'spindled.8 describes every key and no other: missing '
      f'{sorted(keys - man_keys)}, unknown {sorted(man_keys - keys)}')
set_row = next((line for line in readme.splitlines() if line.startswith('| `--set KEY=VALUE`')), '')
readme_keys = set(re.findall(r'`([a-z][a-z0-9-]+)`', set_row))
check(keys == readme_keys, 'README.md\'s --set row names every key and no other: missing '
      f'{sorted(keys - readme_keys)}, unknown {sorted(readme_keys - keys)}')

options = set(re.findall(r'\{ "([a-z-]+)", (?:required|no)_argument', main_c))
check(len(options) > 5, f'{len(options)} long options found in daemon/main.c')
man_opts = set(re.findall(r'\\-\\-([a-z-]+)', man_section(man8, 'OPTIONS')))
check(options <= man_opts, f'spindled.8 OPTIONS has every option: missing {sorted(options - man_opts)}')
readme_opts = set(re.findall(r'^\| `--([a-z-]+)', readme, flags=re.M))
told = options - {'help', 'version', 'verbose'}  # the README points to the man page for these
check(told <= readme_opts, f'README.md\'s option table has every option: missing {sorted(told - readme_opts)}')

if shutil.which('man'):
    for page in ('docs/man/spindled.8', 'docs/man/spindlectl.1'):
        p = subprocess.run(['man', '--warnings', '-l', os.path.join(root, page)], capture_output=True, text=True,
                           env=dict(os.environ, MANWIDTH='80', MAN_KEEP_FORMATTING='0'))
        check(p.returncode == 0 and not p.stderr.strip(), f'{page} renders without warnings: {p.stderr.strip()!r}')
else:
    print('man-db is not installed: the pages\' rendering is not checked here')

sys.exit(1 if failures else 0)
