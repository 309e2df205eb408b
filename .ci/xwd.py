"""Reads X window dumps (`xwd -root -silent`, ZPixmap, 24/32-bit TrueColor) without
ImageMagick, and writes them as PNG: the viewer's real-window check uses it."""
import struct
import sys
import zlib

FIELDS = ("header_size file_version pixmap_format depth width height xoffset byte_order "
          "bitmap_unit bitmap_bit_order bitmap_pad bits_per_pixel bytes_per_line visual_class "
          "red_mask green_mask blue_mask bits_per_rgb colormap_entries ncolors").split()


def read_xwd(path):
    """(width, height, rgb bytes row-major) of an XWD file."""
    data = open(path, "rb").read()
    h = dict(zip(FIELDS, struct.unpack(">20I", data[:80])))
    if h["pixmap_format"] != 2 or h["bits_per_pixel"] not in (24, 32):
        raise ValueError(f"{path}: unsupported XWD layout {h}")
    start = h["header_size"] + 12 * h["ncolors"]
    w, hgt, bpl, bpp = h["width"], h["height"], h["bytes_per_line"], h["bits_per_pixel"] // 8
    shifts = [(m & -m).bit_length() - 1 for m in (h["red_mask"], h["green_mask"], h["blue_mask"])]
    order = "little" if h["byte_order"] == 0 else "big"
    out = bytearray(w * hgt * 3)
    for y in range(hgt):
        row = data[start + y * bpl: start + y * bpl + w * bpp]
        for x in range(w):
            v = int.from_bytes(row[x * bpp:(x + 1) * bpp], order)
            o = (y * w + x) * 3
            out[o], out[o + 1], out[o + 2] = ((v >> s) & 0xFF for s in shifts)
    return w, hgt, bytes(out)


def write_png(path, w, h, rgb):
    raw = b"".join(b"\0" + rgb[y * w * 3:(y + 1) * w * 3] for y in range(h))

    def chunk(kind, body):
        c = struct.pack(">I", len(body)) + kind + body
        return c + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    open(path, "wb").write(png)


if __name__ == "__main__":
    w, h, rgb = read_xwd(sys.argv[1])
    write_png(sys.argv[2], w, h, rgb)
