#!/usr/bin/env python3
"""Follows README.md's "Writing a client" as a new developer would: every
```sh block of that section, in order, in a copy of the source tree (with
`build/` standing for the test's own full build), then checks what they
printed. Two liberties, both for running beside other tests: the socket
path is a private one, and `sleep 1` (the wait for the daemon) waits for
the socket to appear instead.

    test-readme-client.py SOURCE_ROOT BUILD_ROOT
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile


def section_blocks(readme):
    text = open(readme, encoding='utf-8').read()
    start = text.index('\n## Writing a client\n')
    end = text.find('\n## ', start + 1)
    section = text[start:end if end > 0 else len(text)]
    return re.findall(r'```sh\n(.*?)```', section, flags=re.S)


def copy_tree(src, dst):
    """The tracked sources, without build folders or what the README makes
    (at the top), nor caches anywhere."""
    top = re.compile(r'^(build.*|\.git|demo-out|sdk|hello.*)$')

    def ignore(d, names):
        here = top if os.path.samefile(d, src) else None
        return [n for n in names if n == '__pycache__' or (here and here.match(n))]

    shutil.copytree(src, dst, symlinks=True, ignore=ignore)


def main():
    src, build = sys.argv[1], os.path.abspath(sys.argv[2])
    blocks = section_blocks(os.path.join(src, 'README.md'))
    if len(blocks) < 3:
        sys.exit(f'README.md: "Writing a client" has {len(blocks)} sh blocks, expected 3')
    with tempfile.TemporaryDirectory(prefix='spindle-readme-') as tmp:
        tree = os.path.join(tmp, 'spindle')
        copy_tree(src, tree)
        os.symlink(build, os.path.join(tree, 'build'))
        sock = os.path.join(tmp, 'spindle.sock')
        script = '\n'.join(blocks).replace('/tmp/spindle.sock', sock)
        wait = f'for i in $(seq 200); do [ -S {sock} ] && break; sleep 0.1; done'
        script = re.sub(r'^sleep 1\b.*$', wait, script, flags=re.M)
        print(script)
        # A developer's shell: none of the test runner's library paths (an
        # ASan build's libspindle would be found before the one the README
        # builds) nor its socket.
        env = dict(os.environ)
        for k in ('SPINDLE_SOCKET', 'PKG_CONFIG_PATH', 'LISTEN_FDS', 'LISTEN_PID', 'LD_LIBRARY_PATH', 'LD_PRELOAD'):
            env.pop(k, None)
        out_path, err_path = os.path.join(tmp, 'out'), os.path.join(tmp, 'err')
        try:
            with open(out_path, 'w') as out, open(err_path, 'w') as err:  # files: a daemon left running holds no pipe
                r = subprocess.run(['bash', '-euo', 'pipefail', '-c', script], cwd=tree, env=env, stdout=out,
                                   stderr=err, timeout=240)
        finally:
            subprocess.run(['pkill', '-f', sock], check=False)  # the daemon, if a command failed before kill
        r.stdout = open(out_path).read()
        print(r.stdout)
        print(open(err_path).read(), file=sys.stderr)
        if r.returncode != 0:
            sys.exit(f'the README commands failed (exit {r.returncode})')
        shown = re.findall(r'^hello: shown in volume (\d+) \(libspindle ([0-9.]+), protocol (\d+)\)$', r.stdout,
                           flags=re.M)
        if len(shown) != 2:
            sys.exit(f'expected two "hello: shown in volume" lines, got {len(shown)}')
        if not re.search(r'clients', r.stdout):
            sys.exit('spindlectl status printed no status')
        for p in ('sdk/include/spindle/spindle.h', 'sdk/include/spindle/spindle-errors.h',
                  'sdk/include/spindle/spindle-version.h', 'sdk/lib/pkgconfig/spindle.pc'):
            if not os.path.exists(os.path.join(tree, p)):
                sys.exit(f'{p} was not installed')
        print(f'ok: {len(shown)} clients built as the README says were shown ({shown})')


if __name__ == '__main__':
    main()
