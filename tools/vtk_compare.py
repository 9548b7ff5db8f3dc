"""Compares the arrays of two VTK XML files written by mpmice (appended
data, raw or vtkZLibDataCompressor, UInt64 headers), read with Python's
standard library only, following the VTK file-format documentation: an
independent check that a zlib file holds the raw file's values.

    python3 tools/vtk_compare.py RUN_ZLIB/particles_0003.vtu RUN_RAW/particles_0003.vtu
"""
import re, struct, sys, zlib

def read(path):
    b = open(path, 'rb').read()
    m = b.index(b'<AppendedData encoding="raw">')
    us = b.index(b'_', m)
    head = b[:us].decode()
    data = b[us + 1:]
    zl = 'compressor="vtkZLibDataCompressor"' in head
    assert 'header_type="UInt64"' in head
    out = {}
    for tag in re.findall(r'<DataArray [^>]*>', head):
        name = re.search(r'Name="([^"]*)"', tag).group(1)
        off = int(re.search(r'offset="([0-9]+)"', tag).group(1))
        if zl:
            nb, bs, last = struct.unpack_from('<3Q', data, off)
            sizes = struct.unpack_from('<%dQ' % nb, data, off + 24)
            at = off + 24 + 8 * nb
            raw = b''
            for k, s in enumerate(sizes):
                blk = zlib.decompress(data[at:at + s])
                want = last if (k == nb - 1 and last) else bs
                assert len(blk) == want, (name, k, len(blk), want)
                raw += blk
                at += s
        else:
            (n,) = struct.unpack_from('<Q', data, off)
            raw = data[off + 8: off + 8 + n]
        out[name] = raw
    return out, zl

if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, za = read(sys.argv[1]); b, zb = read(sys.argv[2])
    assert a.keys() == b.keys(), (a.keys(), b.keys())
    bad = [k for k in a if a[k] != b[k]]
    print(sys.argv[1], 'zlib' if za else 'raw', 'vs', sys.argv[2], 'zlib' if zb else 'raw',
          len(a), 'arrays', 'IDENTICAL' if not bad else 'DIFFER: %s' % bad)
    sys.exit(1 if bad else 0)
