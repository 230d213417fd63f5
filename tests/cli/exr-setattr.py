#!/usr/bin/env python3
"""Rewrites one string attribute of an OpenEXR file, the way a tampered file would carry it:
exr-setattr.py IN.exr NAME VALUE OUT.exr, or IN.exr NAME --sub REGEX REPLACEMENT OUT.exr (re.sub on
the value, in every part's header). Every header (single- or multi-part) is rewritten and
the chunk offset tables are shifted by the change in the headers' length, so the file stays valid."""
import re
import struct
import sys


def main():
    src, name, dst = sys.argv[1], sys.argv[2].encode(), sys.argv[-1]
    if sys.argv[3] == '--sub':
        def newval(old):
            return re.sub(sys.argv[4], sys.argv[5], old.decode()).encode()
    else:
        def newval(old):
            return sys.argv[3].encode()
    d = open(src, 'rb').read()
    assert d[:4] == b'\x76\x2f\x31\x01', 'not an OpenEXR file'
    multipart = struct.unpack('<I', d[4:8])[0] & 0x1000
    out, i, found = bytearray(d[:8]), 8, 0
    while True:  # headers: attributes up to an empty name; multi-part files end the list with one more
        if d[i] == 0:
            out.append(0)
            i += 1
            if not multipart or d[i] == 0:
                if multipart:
                    out.append(0)
                    i += 1
                break
            continue
        end = d.index(b'\0', i)
        aname = d[i:end]
        tend = d.index(b'\0', end + 1)
        atype = d[end + 1:tend]
        size = struct.unpack('<i', d[tend + 1:tend + 5])[0]
        val = d[tend + 5:tend + 5 + size]
        if aname == name:
            assert atype == b'string', 'not a string attribute'
            val, found = newval(val), found + 1
        out += aname + b'\0' + atype + b'\0' + struct.pack('<i', len(val)) + val
        i = tend + 5 + size
    assert found, 'no attribute ' + name.decode()
    delta = len(out) - i
    first = struct.unpack('<Q', d[i:i + 8])[0]  # the first chunk starts where the offset tables end
    n = (first - i) // 8
    for k in range(n):
        out += struct.pack('<Q', struct.unpack('<Q', d[i + 8 * k:i + 8 * k + 8])[0] + delta)
    out += d[i + 8 * n:]
    open(dst, 'wb').write(out)


main()
