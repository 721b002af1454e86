#!/usr/bin/env python3
"""Writes the seeds of the scan fuzz targets (fuzz/fuzz_scan_*.c): small
phantoms from scripts/make-phantom (NIfTI-1, .nii.gz, NIfTI-2, DICOM
slices in each transfer syntax it writes), variants of their headers
(other voxel types, byte order, units, a 4-D image, the magic of a
header pair, lying sizes, truncations) and raw layouts.

    fuzz/gen_scan_corpus.py [CORPUS]    (default: fuzz/corpus)

Only the scan-nifti, scan-dicom and scan-raw directories are rewritten.
Needs dcmtk's dump2dcm (as make-phantom does). Python 3 standard library
only; the output is reproducible.
"""
import importlib.machinery
import importlib.util
import os
import shutil
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
MAKE_PHANTOM = os.path.join(HERE, '..', 'scripts', 'make-phantom')
N1 = '<i10s18sihcb8h3f4h8f3fhcb4f2i80s24s2h6f12f16s4s'  # make-phantom's NIfTI-1 header


def load_phantom():
    loader = importlib.machinery.SourceFileLoader('make_phantom', MAKE_PHANTOM)
    spec = importlib.util.spec_from_loader('make_phantom', loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def read(path):
    with open(path, 'rb') as f:
        return f.read()


def n1_fields(hdr):
    return list(struct.unpack(N1, hdr[:348]))


# Field indices in N1's tuple: dim at 7..14, datatype 19, bitpix 20,
# scl_slope 31, scl_inter 32, xyzt_units 35, magic 65.
DIM, DATATYPE, BITPIX, SLOPE, INTER, UNITS, MAGIC = 7, 19, 20, 31, 32, 35, 65


def n1_file(fields, data, order='<'):
    return struct.pack(order + N1[1:], *fields) + b'\0\0\0\0' + data


def nifti_seeds(ph, tmp):
    dims, spacing = [8, 6, 4], [1.5, 1.25, 3.0]
    voxels = ph.phantom(dims, spacing)
    paths = {k: os.path.join(tmp, k) for k in ('p.nii', 'p.nii.gz', 'p2.nii')}
    ph.write_nii(paths['p.nii'], dims, spacing, 10, voxels, False)
    ph.write_nii(paths['p.nii.gz'], dims, spacing, 10, voxels, True)
    ph.write_nii2(paths['p2.nii'], dims, spacing, 10, voxels)
    nii = read(paths['p.nii'])
    seeds = {'phantom.nii': nii, 'phantom.nii.gz': read(paths['p.nii.gz']), 'phantom-nifti2.nii': read(paths['p2.nii'])}
    seeds['truncated.nii'] = nii[:352 + len(voxels)]
    f = n1_fields(nii)
    data = nii[352:]
    variant = list(f)
    variant[DIM + 3] = 64
    seeds['lying-dims.nii'] = n1_file(variant, data)
    small = list(f)
    small[DIM:DIM + 8] = [3, 2, 2, 1, 1, 1, 1, 1]
    for name, dt, bits, body, slope, inter in (
            ('int8.nii', 256, 8, bytes([0x80, 0xff, 0, 0x7f]), 0, 0),
            ('uint8-scaled.nii', 2, 8, bytes([0, 1, 2, 255]), 2.5, -1),
            ('uint16-shift.nii', 512, 16, struct.pack('<4H', 0, 1000, 40000, 65535), 1, -32768),
            ('int32.nii', 8, 32, struct.pack('<4i', -1000, 0, 3000, 70000), 0, 0),
            ('uint32.nii', 768, 32, struct.pack('<4I', 0, 1, 65535, 65536), 0, 0),
            ('float32.nii', 16, 32, struct.pack('<4f', -1.5, 0, float('nan'), 3e38), 0, 0),
            ('float64.nii', 64, 64, struct.pack('<4d', -1.5, 0, 1e300, 0.25), 0, 0),
            ('rgb24.nii', 128, 24, bytes(range(12)), 0, 0),
            ('rgba32.nii', 2304, 32, bytes(range(16)), 0, 0),
            ('complex64.nii', 32, 64, bytes(32), 0, 0)):
        v = list(small)
        v[DATATYPE], v[BITPIX], v[SLOPE], v[INTER] = dt, bits, slope, inter
        seeds[name] = n1_file(v, body)
    v = list(f)
    v[DIM:DIM + 5] = [4, 8, 6, 2, 2]
    seeds['4d.nii'] = n1_file(v, data)
    v = list(f)
    v[MAGIC] = b'ni1\0'
    seeds['pair-magic.nii'] = n1_file(v, data)
    v = list(f)
    v[MAGIC] = b'\0\0\0\0'
    seeds['analyze.nii'] = n1_file(v, data)
    v = list(f)
    v[UNITS] = 3  # micrometres
    seeds['microns.nii'] = n1_file(v, data)
    swapped = bytearray(data)
    swapped[0::2], swapped[1::2] = data[1::2], data[0::2]
    seeds['big-endian.nii'] = n1_file(f, bytes(swapped), '>')
    return seeds


def dicom_seeds(ph, tmp):
    out = os.path.join(tmp, 'dicom')
    dims, spacing = [8, 6, 3], [0.75, 0.5, 2.0]
    ph.write_dicom(out, dims, spacing, 15, ph.phantom(dims, spacing), 'fuzz')
    seeds = {}
    for name in sorted(os.listdir(out)):
        data = read(os.path.join(out, name))
        syntax = {b'1.2.840.10008.1.2\0': 'implicit', b'1.2.840.10008.1.2.1': 'explicit-le',
                  b'1.2.840.10008.1.2.2': 'explicit-be'}
        kind = next((v for k, v in syntax.items() if k in data), 'unknown')
        seeds[f'phantom-slice-{kind}.dcm'] = data
    first = seeds[sorted(seeds)[0]]
    seeds['truncated.dcm'] = first[:len(first) - 40]
    seeds['header-only.dcm'] = first[:400]
    seeds.update(dump_variants(ph, tmp, dims, spacing))
    return seeds


def dump_variants(ph, tmp, dims, spacing):
    """Slices that make-phantom does not write: signed, 8-bit, refused kinds."""
    row, col, pos = ph.geometry(dims, spacing, 0)
    raw16 = os.path.join(tmp, 'px16.raw')
    raw8 = os.path.join(tmp, 'px8.raw')
    with open(raw16, 'wb') as f:
        f.write(struct.pack(f'<{dims[0] * dims[1]}h', *range(-24, 24)))
    with open(raw8, 'wb') as f:
        f.write(bytes(range(dims[0] * dims[1])))
    base = ph.slice_dump(dims, spacing, row, col, pos[0], 0, 'fuzz-variants', raw16)
    variants = {
        'signed.dcm': {'(0028,0103)': '(0028,0103) US 1', '(0028,0101)': '(0028,0101) US 16',
                       '(0028,0102)': '(0028,0102) US 15', '(0028,1052)': '(0028,1052) DS [0]'},
        'uint8.dcm': {'(0028,0100)': '(0028,0100) US 8', '(0028,0101)': '(0028,0101) US 8',
                      '(0028,0102)': '(0028,0102) US 7', '(7fe0,0010)': f'(7fe0,0010) OB ={raw8}'},
        'scaled.dcm': {'(0028,1053)': '(0028,1053) DS [0.5]', '(0028,1052)': '(0028,1052) DS [-10.25]'},
        'monochrome1.dcm': {'(0028,0004)': '(0028,0004) CS MONOCHROME1'},
        'multiframe.dcm': {'(0028,0002)': '(0028,0002) US 1\n(0028,0008) IS [2]'},
        'no-position.dcm': {'(0020,0032)': ''},
        'bad-orientation.dcm': {'(0020,0037)': '(0020,0037) DS [1\\0\\0\\1\\0\\0]'},
    }
    seeds = {}
    for name, changes in variants.items():
        lines = []
        for line in base.splitlines():
            key = line[:11]
            lines.append(changes.get(key, line))
        dump, out = os.path.join(tmp, name + '.txt'), os.path.join(tmp, name)
        with open(dump, 'w') as f:
            f.write('\n'.join(l for l in lines if l) + '\n')
        subprocess.run(['dump2dcm', '-q', '+te', dump, out], check=True)
        seeds[name] = read(out)
    return seeds


def num(v, wide=False):
    """fuzz_num() (fuzz_num64() when wide): one byte below 0x80, else 0x80
    and the value in 4 (8) bytes."""
    return bytes([v]) if v < 0x80 else b'\x80' + struct.pack('<Q' if wide else '<I', v)


def raw(dims, type_, spacing, flags, offset, body):
    return b''.join(num(d) for d in dims) + bytes([type_, *spacing, flags]) + num(offset, True) + body


def raw_seeds():
    return {
        'u16-big-endian': raw([2, 2, 1], 2, [16, 32, 48], 1, 0, bytes([1, 2, 0x80, 0, 0xff, 0xfe, 0, 7])),
        'i16-little-endian': raw([2, 1, 1], 3, [16, 16, 16], 0, 0, bytes([0xff, 0xff, 1, 0])),
        'u8-offset': raw([3, 1, 1], 1, [8, 8, 8], 0, 2, bytes(range(5))),
        'f32-big-endian': raw([1, 1, 2], 4, [16, 16, 16], 1, 0, bytes([0x3f, 0xc0, 0, 0, 0xc1, 0x20, 0, 0])),
        'rgba8': raw([1, 2, 1], 5, [16, 16, 16], 1, 0, bytes(range(8))),
        'short-file': raw([4, 4, 4], 2, [16, 16, 16], 0, 0, bytes(10)),
        'offset-past-end': raw([1, 1, 1], 1, [16, 16, 16], 0, 1 << 40, bytes(4)),
        'too-big': raw([4096, 4096, 4096], 1, [16, 16, 16], 0, 0, bytes(4)),
        'nan-spacing': raw([1, 1, 1], 1, [16, 255, 16], 0, 0, bytes(1)),
        'zero-dim': raw([0, 1, 1], 1, [16, 16, 16], 0, 0, bytes(1)),
        'bad-type': raw([1, 1, 1], 9, [16, 16, 16], 0, 0, bytes(4)),
    }


def write_dir(path, seeds):
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    for name, data in sorted(seeds.items()):
        with open(os.path.join(path, name), 'wb') as f:
            f.write(data)


def main():
    corpus = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, 'corpus')
    ph = load_phantom()
    with tempfile.TemporaryDirectory() as tmp:
        write_dir(os.path.join(corpus, 'scan-nifti'), nifti_seeds(ph, tmp))
        write_dir(os.path.join(corpus, 'scan-dicom'), dicom_seeds(ph, tmp))
    write_dir(os.path.join(corpus, 'scan-raw'), raw_seeds())


if __name__ == '__main__':
    main()
