"""PNG bytes of an RGB image, every row with the same filter: :func:`rgb_png`.

Pillow chooses a filter for every row by trying all five (its adaptive filtering), which
costs more than the compression on a chart of flat colours. One filter for every row,
``Up`` (each byte less the byte above it), keeps the runs of a chart's rows compressible:
on the build's depth charts (1200 x 400) the file is about 10 % larger than Pillow's and
is written in about half the time. The pixels are the image's, bit for bit.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

#: The eight bytes every PNG file starts with.
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: IHDR: 8 bits per sample, colour type 2 (RGB), deflate, filter method 0 (the five row
#: filters), no interlace.
_BIT_DEPTH, _RGB, _DEFLATE, _FILTER_SET, _NO_INTERLACE = 8, 2, 0, 0, 0
#: The filter type byte of a row filtered against the row above it.
UP_FILTER = 2


def _chunk(kind: bytes, data: bytes) -> bytes:
    """One PNG chunk: length, type, data and the CRC-32 of type and data."""
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data)))


def rgb_png(pixels: np.ndarray, level: int) -> bytes:
    """Encode an RGB image as a PNG file, every row ``Up``-filtered.

    Parameters
    ----------
    pixels
        ``(H, W, 3) uint8``: the image, rows from the top.
    level
        zlib compression level, 0 (none) to 9 (smallest).

    Returns
    -------
    bytes
        The PNG file.

    Raises
    ------
    ValueError
        When ``pixels`` is not an ``(H, W, 3) uint8`` array of at least one pixel.
    """
    if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] != 3 or not pixels.size:
        raise ValueError(f"an RGB image is (H, W, 3) uint8 with a pixel at least; got "
                         f"{pixels.shape} {pixels.dtype}")
    height, width, _ = pixels.shape
    rows = pixels.reshape(height, width * 3)
    filtered = np.empty((height, 1 + width * 3), dtype=np.uint8)
    filtered[:, 0] = UP_FILTER
    filtered[0, 1:] = rows[0]
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])        # modulo 256, as PNG's Up
    header = struct.pack(">IIBBBBB", width, height, _BIT_DEPTH, _RGB, _DEFLATE, _FILTER_SET,
                         _NO_INTERLACE)
    return b"".join((PNG_SIGNATURE, _chunk(b"IHDR", header),
                     _chunk(b"IDAT", zlib.compress(filtered.tobytes(), level)),
                     _chunk(b"IEND", b"")))
