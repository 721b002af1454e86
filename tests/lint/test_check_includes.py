#!/usr/bin/env python3
# Self-test for scripts/check-includes: builds small source trees in a
# temporary directory and checks the exit status and messages.
#   test_check_includes.py [path/to/check-includes]
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.abspath(sys.argv.pop(1) if len(sys.argv) > 1 else
                         os.path.join(HERE, '..', '..', 'scripts', 'check-includes'))


def make_tree(root, files):
    for path, text in files.items():
        full = os.path.join(root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, 'w') as f:
            f.write(text)


def inc(*names):
    return ''.join(f'#include "{n}"\n' for n in names)


# A tree without cycles or rule violations: server ties clients and devices
# together; a generated header that is not in the tree is skipped.
CLEAN = {
    'common/log.h': '#pragma once\n',
    'common/log.c': inc('log.h'),
    'daemon/server.h': '#pragma once\n',
    'daemon/server.c': '#include <stdio.h>\n' + inc('server.h', 'client.h', 'devices.h', 'log.h'),
    'daemon/client.h': inc('spindle-protocol.h'),
    'daemon/client.c': inc('client.h', 'log.h'),
    'daemon/devices.h': '#pragma once\n',
    'daemon/devices.c': inc('devices.h', 'render.h', 'projector.h'),
    'daemon/render/render.h': '#pragma once\n',
    'daemon/render/render.c': inc('render.h', 'log.h'),
    'daemon/render/render_cpu.c': inc('render.h'),
    'drivers/projector.h': '#pragma once\n',
    'drivers/proj_sim.c': inc('projector.h', 'log.h'),
    # /* #include "server.h" */ in a comment is not an include.
    'drivers/sync.c': '/* not a real\n#include "server.h"\n */\n',
}


class CheckIncludes(unittest.TestCase):
    def run_on(self, files, *args):
        with tempfile.TemporaryDirectory() as root:
            make_tree(root, files)
            p = subprocess.run([sys.executable, SCRIPT, '--root', root, *args],
                               capture_output=True, text=True)
        return p.returncode, p.stdout, p.stderr

    def test_clean(self):
        rc, out, err = self.run_on(CLEAN)
        self.assertEqual(rc, 0, out + err)
        # server client devices render render_cpu projector proj_sim sync;
        # edges: server->client, server->devices, devices->render,
        # devices->projector, render_cpu->render, proj_sim->projector.
        self.assertEqual(out.strip(), '8 modules, 6 edges, no cycles')

    def test_two_module_cycle(self):
        files = dict(CLEAN)
        files['daemon/client.c'] = inc('client.h', 'log.h', 'server.h')
        rc, out, _ = self.run_on(files)
        self.assertEqual(rc, 1)
        self.assertIn('cycle: daemon/client -> daemon/server -> daemon/client', out)
        self.assertIn('daemon/client.c:3: #include "server.h"', out)
        self.assertIn('daemon/server.c:3: #include "client.h"', out)
        self.assertIn('1 cycle(s)', out)

    def test_three_module_cycle_through_headers(self):
        files = dict(CLEAN)
        files['daemon/a.h'] = inc('b.h')
        files['daemon/b.h'] = inc('c.h')
        files['daemon/c.c'] = inc('c.h', 'a.h')
        files['daemon/c.h'] = ''
        rc, out, _ = self.run_on(files)
        self.assertEqual(rc, 1)
        self.assertIn('cycle: daemon/a -> daemon/b -> daemon/c -> daemon/a', out)
        self.assertIn('daemon/a.h:1: #include "b.h"', out)
        self.assertIn('daemon/c.c:2: #include "a.h"', out)

    def test_lone_header_is_a_module(self):
        # x.c includes x_int.h which includes x.h: x -> x_int -> x.
        files = dict(CLEAN)
        files['drivers/x.h'] = ''
        files['drivers/x.c'] = inc('x.h', 'x_int.h')
        files['drivers/x_int.h'] = inc('x.h')
        rc, out, _ = self.run_on(files)
        self.assertEqual(rc, 1)
        self.assertIn('cycle: drivers/x -> drivers/x_int -> drivers/x', out)

    def test_cycle_outside_checked_dirs_ignored(self):
        files = dict(CLEAN)
        files['daemon/client.c'] = inc('client.h', 'server.h')
        rc, out, _ = self.run_on(files, 'drivers')
        self.assertEqual(rc, 0, out)
        self.assertIn('no cycles', out)

    def test_only_server_includes_client_and_devices(self):
        files = dict(CLEAN)
        files['daemon/main.c'] = inc('devices.h', 'client.h')
        rc, out, _ = self.run_on(files)
        self.assertEqual(rc, 1)
        self.assertIn('rule: daemon/main.c: includes both daemon/client.h and daemon/devices.h', out)
        self.assertIn('only daemon/server.c may include both', out)
        self.assertNotIn('rule: daemon/server.c', out)

    def test_device_side_must_not_include_server_or_client(self):
        files = dict(CLEAN)
        files['daemon/pipeline.c'] = inc('server.h')
        files['daemon/render/render_cpu.c'] = inc('render.h', 'client.h')
        files['drivers/proj_sim.c'] = inc('projector.h', 'server.h')
        rc, out, _ = self.run_on(files)
        self.assertEqual(rc, 1)
        self.assertIn('rule: daemon/pipeline.c:1: #include "server.h" (daemon/server.h)', out)
        self.assertIn('rule: daemon/render/render_cpu.c:2: #include "client.h" (daemon/client.h)', out)
        self.assertIn('rule: drivers/proj_sim.c:2: #include "server.h" (daemon/server.h)', out)
        self.assertIn('3 rule violation(s)', out)
        self.assertNotIn('cycle:', out)

    def test_graph_and_dot(self):
        files = dict(CLEAN)
        files['daemon/client.c'] = inc('client.h', 'server.h')
        rc, out, err = self.run_on(files, '--graph')
        self.assertEqual(rc, 1)
        self.assertIn('daemon/server -> daemon/devices  (daemon/server.c:4)', out)
        self.assertIn('daemon/client -> daemon/server  [cycle]', out)
        self.assertIn('cycle: daemon/client -> daemon/server -> daemon/client', err)
        rc, out, err = self.run_on(CLEAN, '--dot')
        self.assertEqual(rc, 0)
        self.assertTrue(out.startswith('digraph includes {'), out)
        self.assertIn('"daemon/server" -> "daemon/client";', out)
        self.assertIn('no cycles', err)

    def test_decls(self):
        # render.h declares render_cpu_create(), defined in render_cpu.c.
        files = dict(CLEAN)
        files['daemon/render/render.h'] = 'struct renderer *render_cpu_create(int threads);\n'
        files['daemon/render/render.c'] = inc('render.h') + 'int f(void)\n{\n\treturn render_cpu_create(1) != 0;\n}\n'
        files['daemon/render/render_cpu.c'] = inc('render.h') + 'struct renderer *render_cpu_create(int threads)\n{\n\treturn 0;\n}\n'
        rc, out, _ = self.run_on(files)
        self.assertEqual(rc, 0, out)
        rc, out, _ = self.run_on(files, '--decls')
        self.assertEqual(rc, 1)
        self.assertIn('cycle: daemon/render/render -> daemon/render/render_cpu -> daemon/render/render', out)
        self.assertIn('(declares render_cpu_create(), defined in daemon/render/render_cpu.c)', out)


if __name__ == '__main__':
    unittest.main(verbosity=2)
