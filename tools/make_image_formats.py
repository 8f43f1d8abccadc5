#!/usr/bin/env python3
"""Writes the image-format test textures of pbrt-scenes/verify/textures.

    python3 tools/make_image_formats.py [OUT_DIR]     # default pbrt-scenes/verify

Every texture is the same 16 x 8 picture (a red gradient left to right, a green one
top to bottom, a white block in the top left corner, so that a flipped or mirrored
read shows), stored as:

- fmt-bottomup.tga: uncompressed 24-bit TGA, rows bottom to top (TGA's default);
- fmt-rle.tga: run-length encoded 32-bit TGA, rows top to bottom;
- fmt.pfm: little-endian PFM (rows bottom to top, as PFM stores them), the values
  linear (the sRGB decoding of the 8-bit picture), scale -2 so the values are halved;
- fmt.hdr: Radiance RGBE, flat scanlines, the values linear;
- fmt.bmp: 24-bit BMP, rows bottom to top;
- fmt.jpg: JPEG, quality 95 (needs Pillow);
- fmt.png: 8-bit PNG;
- fmt-alpha.png: the picture with an alpha channel (opaque in a disc, half clear in a
  band across the middle, clear elsewhere), for pbrt-v4's float textures, which take it;
- fmt-sky.png: a 16 x 8 environment map, a sky of 8-bit value 128 over a ground of 64;
- fmt-sky-square.png: an 8 x 8 one for pbrt-v4 (equal-area squares only), 128 but for
  one quarter of 64;
- fmt-grey.exr: a luminance-only EXR (one channel, `Y`, 32-bit float), a ramp across
  and down with a bright block in the top left corner, as roughness and mask maps are
  often saved;
- fmt-rgba.exr: the picture's linear values as R, G and B with fmt-alpha.png's alpha
  as A (32-bit float), for pbrt-v4's float textures, which take the alpha;
- fmt.gif: GIF with the picture's own palette (needs Pillow);
- fmt.ppm: binary PPM (P6); fmt-grey.pgm: binary PGM (P5) of the picture's green;
- fmt.qoi: QOI, RGB, sRGB; fmt-linear.qoi: the same bytes marked linear;
  fmt-alpha.qoi: RGBA with fmt-alpha.png's alpha, sRGB.

Standard library only, except the JPEG and the GIF.
"""
import math
import os
import struct
import sys
import zlib

W, H = 16, 8


def picture():
    """Rows top to bottom of (r, g, b) bytes."""
    rows = []
    for y in range(H):
        row = []
        for x in range(W):
            if x < 3 and y < 2:
                row.append((255, 255, 255))
            else:
                row.append((40 + 14 * x, 30 + 30 * y, 90))
        rows.append(row)
    return rows


def linear(b):
    v = b / 255.0
    return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4


def png(path, rows):
    """8-bit RGB, or RGBA where the pixels have four values."""
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    colour = 6 if len(rows[0][0]) == 4 else 2
    header = struct.pack(">IIBBBBB", len(rows[0]), len(rows), 8, colour, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def tga_bottom_up(path, rows):
    header = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, W, H, 24, 0)
    data = b"".join(bytes((b, g, r)) for row in reversed(rows) for (r, g, b) in row)
    with open(path, "wb") as f:
        f.write(header + data)


def tga_rle_top_down(path, rows):
    header = struct.pack("<BBBHHBHHHHBB", 0, 0, 10, 0, 0, 0, 0, 0, W, H, 32, 0x28)
    out = bytearray()
    for row in rows:
        x = 0
        while x < W:
            n = 1
            while x + n < W and n < 128 and row[x + n] == row[x]:
                n += 1
            r, g, b = row[x]
            if n > 1:
                out += bytes((0x80 | (n - 1), b, g, r, 255))
                x += n
            else:
                out += bytes((0, b, g, r, 255))
                x += 1
    with open(path, "wb") as f:
        f.write(header + bytes(out))


def pfm(path, rows):
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-2.0\n" % (W, H))
        for row in reversed(rows):
            for px in row:
                f.write(struct.pack("<3f", *(linear(c) / 2.0 for c in px)))


def rgbe(rgb):
    m = max(rgb)
    if m < 1e-32:
        return bytes(4)
    mantissa, exponent = math.frexp(m)
    scale = mantissa * 256.0 / m
    return bytes([int(c * scale) for c in rgb] + [exponent + 128])


def hdr(path, rows):
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
        for row in rows:
            for px in row:
                f.write(rgbe([linear(c) for c in px]))


def bmp(path, rows):
    stride = (3 * W + 3) & ~3
    data = b"".join(
        bytes(c for (r, g, b) in row for c in (b, g, r)) + bytes(stride - 3 * W) for row in reversed(rows)
    )
    header = b"BM" + struct.pack("<IHHI", 54 + len(data), 0, 0, 54)
    info = struct.pack("<IiiHHIIiiII", 40, W, H, 1, 24, 0, len(data), 2835, 2835, 0, 0)
    with open(path, "wb") as f:
        f.write(header + info + data)


def jpeg(path, rows):
    from PIL import Image

    img = Image.new("RGB", (W, H))
    img.putdata([px for row in rows for px in row])
    img.save(path, quality=95, subsampling=0)


def gif(path, rows):
    from PIL import Image

    colours = sorted({px for row in rows for px in row})
    img = Image.new("P", (W, H))
    img.putpalette([c for px in colours for c in px])
    img.putdata([colours.index(px) for row in rows for px in row])
    img.save(path)


def pnm(path, rows, grey=False):
    """Binary PPM (P6), or with `grey` a PGM (P5) of the green channel."""
    data = bytes(px[1] if grey else c for row in rows for px in row for c in ((0,) if grey else px))
    with open(path, "wb") as f:
        f.write(b"%s\n%d %d\n255\n" % (b"P5" if grey else b"P6", W, H) + data)


def qoi(path, rows, linear_values=False):
    """QOI, every pixel a literal (QOI_OP_RGB or QOI_OP_RGBA), sRGB unless marked linear."""
    channels = len(rows[0][0])
    out = bytearray(b"qoif" + struct.pack(">IIBB", W, H, channels, 1 if linear_values else 0))
    for row in rows:
        for px in row:
            out += bytes((0xFE if channels == 3 else 0xFF,) + tuple(px))
    with open(path, "wb") as f:
        f.write(bytes(out) + b"\x00" * 7 + b"\x01")


def exr(path, channels):
    """An uncompressed scanline EXR of 32-bit float channels: {name: rows of values}."""
    names = sorted(channels)  # EXR stores channels in alphabetical order

    def attribute(name, kind, value):
        return name.encode() + b"\x00" + kind.encode() + b"\x00" + struct.pack("<i", len(value)) + value

    chlist = b"".join(n.encode() + b"\x00" + struct.pack("<iB3xii", 2, 0, 1, 1) for n in names) + b"\x00"
    window = struct.pack("<4i", 0, 0, W - 1, H - 1)
    header = (
        attribute("channels", "chlist", chlist)
        + attribute("compression", "compression", b"\x00")
        + attribute("dataWindow", "box2i", window)
        + attribute("displayWindow", "box2i", window)
        + attribute("lineOrder", "lineOrder", b"\x00")
        + attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + attribute("screenWindowCenter", "v2f", struct.pack("<2f", 0.0, 0.0))
        + attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
        + b"\x00"
    )
    start = 8 + len(header) + 8 * H
    lines = []
    for y in range(H):
        data = b"".join(struct.pack("<%df" % W, *channels[n][y]) for n in names)
        lines.append(struct.pack("<ii", y, len(data)) + data)
    offsets, at = [], start
    for line in lines:
        offsets.append(at)
        at += len(line)
    with open(path, "wb") as f:
        f.write(b"\x76\x2f\x31\x01" + struct.pack("<i", 2) + header)
        f.write(struct.pack("<%dQ" % H, *offsets) + b"".join(lines))


def main():
    out = os.path.join(sys.argv[1] if len(sys.argv) > 1 else "pbrt-scenes/verify", "textures")
    os.makedirs(out, exist_ok=True)
    rows = picture()
    png(os.path.join(out, "fmt.png"), rows)
    tga_bottom_up(os.path.join(out, "fmt-bottomup.tga"), rows)
    tga_rle_top_down(os.path.join(out, "fmt-rle.tga"), rows)
    pfm(os.path.join(out, "fmt.pfm"), rows)
    hdr(os.path.join(out, "fmt.hdr"), rows)
    bmp(os.path.join(out, "fmt.bmp"), rows)
    jpeg(os.path.join(out, "fmt.jpg"), rows)
    sky = [[(128, 128, 128)] * W for _ in range(H // 2)] + [[(64, 64, 64)] * W for _ in range(H // 2)]
    png(os.path.join(out, "fmt-sky.png"), sky)
    # Opaque in a disc, clear outside it, half clear in a band across the middle.
    alpha = [
        [px + (255 if (x - 7.5) ** 2 + (y - 3.5) ** 2 * 4 < 30 else 128 if y in (3, 4) else 0,) for x, px in enumerate(row)]
        for y, row in enumerate(rows)
    ]
    png(os.path.join(out, "fmt-alpha.png"), alpha)
    gif(os.path.join(out, "fmt.gif"), rows)
    pnm(os.path.join(out, "fmt.ppm"), rows)
    pnm(os.path.join(out, "fmt-grey.pgm"), rows, grey=True)
    qoi(os.path.join(out, "fmt.qoi"), rows)
    qoi(os.path.join(out, "fmt-linear.qoi"), rows, linear_values=True)
    qoi(os.path.join(out, "fmt-alpha.qoi"), alpha)
    square = [[(128, 128, 128) if x < 4 or y < 4 else (64, 64, 64) for x in range(8)] for y in range(8)]
    png(os.path.join(out, "fmt-sky-square.png"), square)
    grey = [[0.9 if x < 3 and y < 2 else 0.05 + 0.04 * x + 0.05 * y for x in range(W)] for y in range(H)]
    exr(os.path.join(out, "fmt-grey.exr"), {"Y": grey})
    exr(
        os.path.join(out, "fmt-rgba.exr"),
        {
            "R": [[linear(px[0]) for px in row] for row in rows],
            "G": [[linear(px[1]) for px in row] for row in rows],
            "B": [[linear(px[2]) for px in row] for row in rows],
            "A": [[px[3] / 255.0 for px in row] for row in alpha],
        },
    )


if __name__ == "__main__":
    main()
