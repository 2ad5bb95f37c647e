"""PNG of 8-bit RGB images with the standard library only (zlib + struct): the encoding the
protocol's images travel in. encode() writes filter type 0 rows; decode() reads any 8-bit RGB
PNG without interlace (all five filter types), checking every chunk's CRC."""
import struct
import zlib

_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class PngError(ValueError):
    pass


def _chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data +
            struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def encode(width, height, rgb, level=6):
    """PNG bytes of a width x height image, rgb: bytes of R, G, B per pixel, rows from the top."""
    stride = 3 * width
    if width <= 0 or height <= 0 or len(rgb) != stride * height:
        raise PngError("rgb holds %d bytes, not %d x %d x 3" % (len(rgb), width, height))
    raw = bytearray()
    view = memoryview(rgb)
    for y in range(height):
        raw.append(0)  # filter type 0: the row as it is
        raw += view[y * stride:(y + 1) * stride]
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit, RGB, no interlace
    return (_SIGNATURE + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", zlib.compress(bytes(raw), level)) +
            _chunk(b"IEND", b""))


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def decode(data):
    """(width, height, rgb bytes) of an 8-bit RGB PNG; PngError for anything else."""
    if data[:8] != _SIGNATURE:
        raise PngError("not a PNG (signature)")
    pos, ihdr, idat = 8, None, bytearray()
    while True:
        if pos + 8 > len(data):
            raise PngError("truncated PNG (no IEND)")
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        crc_at = pos + 8 + length
        if len(body) != length or crc_at + 4 > len(data):
            raise PngError("truncated chunk %r" % kind)
        (crc,) = struct.unpack(">I", data[crc_at:crc_at + 4])
        if crc != zlib.crc32(kind + body) & 0xFFFFFFFF:
            raise PngError("bad CRC in chunk %r" % kind)
        pos = crc_at + 4
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    if ihdr is None:
        raise PngError("no IHDR")
    width, height, depth, colour, _, _, interlace = ihdr
    if depth != 8 or colour != 2 or interlace != 0:
        raise PngError("not 8-bit RGB without interlace (depth %d, colour type %d, interlace %d)"
                       % (depth, colour, interlace))
    raw = zlib.decompress(bytes(idat))
    stride = 3 * width
    if len(raw) != (stride + 1) * height:
        raise PngError("image data holds %d bytes, not %d" % (len(raw), (stride + 1) * height))
    out = bytearray(stride * height)
    prev = bytearray(stride)
    for y in range(height):
        ftype = raw[y * (stride + 1)]
        row = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if ftype == 0:
            pass
        elif ftype == 1:
            for i in range(3, stride):
                row[i] = (row[i] + row[i - 3]) & 0xFF
        elif ftype == 2:
            for i in range(stride):
                row[i] = (row[i] + prev[i]) & 0xFF
        elif ftype == 3:
            for i in range(stride):
                left = row[i - 3] if i >= 3 else 0
                row[i] = (row[i] + ((left + prev[i]) >> 1)) & 0xFF
        elif ftype == 4:
            for i in range(stride):
                left = row[i - 3] if i >= 3 else 0
                upleft = prev[i - 3] if i >= 3 else 0
                row[i] = (row[i] + _paeth(left, prev[i], upleft)) & 0xFF
        else:
            raise PngError("unknown filter type %d in row %d" % (ftype, y))
        out[y * stride:(y + 1) * stride] = row
        prev = row
    return width, height, bytes(out)
