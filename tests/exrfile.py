"""An OpenEXR reader of the tests' own, independent of the code under test (host/io): one channel of
a single-part scanline file, uncompressed or ZIP (one or sixteen rows a chunk), as rows of floats.
Written from the file format's documentation (openexr.com, "OpenEXR File Layout").
"""
import struct
import zlib

ROWS_PER_CHUNK = {0: 1, 2: 1, 3: 16}  # NO_COMPRESSION, ZIPS_COMPRESSION, ZIP_COMPRESSION


def unzip(data, size):
    """A ZIP chunk's bytes: inflated, the predictor undone (each byte the previous plus its delta
    less 128), then the two halves interleaved (the even bytes were stored first)."""
    if len(data) == size:  # stored as is when deflating did not make it smaller
        return data
    t = bytearray(zlib.decompress(data))
    for i in range(1, len(t)):
        t[i] = (t[i - 1] + t[i] - 128) & 255
    out = bytearray(len(t))
    half = (len(t) + 1) // 2
    out[0::2], out[1::2] = t[:half], t[half:]
    return bytes(out)


def read_exr_channel(path, channel):
    d = open(path, "rb").read()
    assert struct.unpack_from("<I", d, 0)[0] == 20000630, f"{path}: not an OpenEXR file"
    assert not struct.unpack_from("<I", d, 4)[0] & 0x1A00, f"{path}: tiled, deep or multi-part"
    at, attrs = 8, {}
    while d[at] != 0:
        name_end = d.index(b"\0", at)
        name = d[at:name_end].decode()
        type_end = d.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", d, type_end + 1)[0]
        attrs[name] = d[type_end + 5:type_end + 5 + size]
        at = type_end + 5 + size
    at += 1
    compression = attrs["compression"][0]
    assert compression in ROWS_PER_CHUNK, f"{path}: compression {compression} (none or zip read here)"
    chans, c = [], 0
    cl = attrs["channels"]
    while cl[c] != 0:
        e = cl.index(b"\0", c)
        chans.append((cl[c:e].decode(), struct.unpack_from("<i", cl, e + 1)[0]))
        c = e + 17
    assert channel in [n for n, _ in chans], f"{path}: no channel {channel}"
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    per = ROWS_PER_CHUNK[compression]
    offsets = struct.unpack_from(f"<{(h + per - 1) // per}Q", d, at)
    out = []
    for k, off in enumerate(offsets):
        rows = min(per, h - k * per)
        n = struct.unpack_from("<i", d, off + 4)[0]
        block = d[off + 8:off + 8 + n]
        if compression:
            block = unzip(block, rows * w * sum(2 if t == 1 else 4 for _, t in chans))
        pos = 0
        for _ in range(rows):
            for name, t in chans:
                if name == channel:
                    out.append(list(struct.unpack_from(f"<{w}" + {0: "I", 1: "e", 2: "f"}[t], block, pos)))
                pos += w * (2 if t == 1 else 4)
    return out
