"""Independent oracles for the hardware-model tests (and tests of the oracles themselves).

Nothing here imports ``rosfpga_lab.hw``: frames are written by the message layer's
``serialize`` and the morphology oracle is a brute-force loop over the window.
"""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from rosfpga_lab.msg import default_registry, deserialize, serialize

REG = default_registry()
CHANNELS = {"rgba8": 4, "bgra8": 4, "rgb8": 3, "bgr8": 3, "mono8": 1}


def image_msg(image: np.ndarray, encoding: str, *, seq: int = 0, stamp: tuple[int, int] = (0, 0),
              frame_id: str = "", is_bigendian: int = 0, step: int | None = None,
              height: int | None = None, width: int | None = None,
              data: bytes | None = None) -> dict:
    """A sensor_msgs/Image value (fields overridable to build bad frames)."""
    rows, cols = image.shape[:2]
    return {
        "header": {"seq": seq, "stamp": {"secs": stamp[0], "nsecs": stamp[1]}, "frame_id": frame_id},
        "height": rows if height is None else height,
        "width": cols if width is None else width,
        "encoding": encoding,
        "is_bigendian": is_bigendian,
        "step": cols * CHANNELS.get(encoding, 1) if step is None else step,
        "data": image.tobytes() if data is None else data,
    }


def tcpros_frame(value: dict) -> bytes:
    """4-byte little-endian length + the message layer's serialization of ``value``."""
    body = serialize(REG, "sensor_msgs/Image", value)
    return len(body).to_bytes(4, "little") + body


def decode_frame(frame: bytes) -> dict:
    """The message layer's decoding of a TCPROS frame (length checked)."""
    assert int.from_bytes(frame[:4], "little") == len(frame) - 4
    return deserialize(REG, "sensor_msgs/Image", frame[4:])


def morph_oracle(image: np.ndarray, op: str, kw: int, kh: int) -> np.ndarray:
    """Max (dilate) / min (erode) over the in-image part of a kw x kh window anchored at its centre."""
    img = image.reshape(image.shape[0], image.shape[1], -1)
    rows, cols = img.shape[:2]
    ax, ay = kw // 2, kh // 2
    out = np.empty_like(img)
    pick = np.max if op == "dilate" else np.min
    for r in range(rows):
        for c in range(cols):
            r0, r1 = max(0, r - ay), min(rows, r - ay + kh)
            c0, c1 = max(0, c - ax), min(cols, c - ax + kw)
            out[r, c] = pick(img[r0:r1, c0:c1].reshape(-1, img.shape[2]), axis=0)
    return out


@st.composite
def images(draw, max_side: int = 9, encodings: tuple[str, ...] = tuple(CHANNELS)) -> tuple[np.ndarray, str]:
    """(image, encoding) with random size 1..max_side and random content."""
    encoding = draw(st.sampled_from(encodings))
    rows = draw(st.integers(1, max_side))
    cols = draw(st.integers(1, max_side))
    raw = draw(st.binary(min_size=rows * cols * CHANNELS[encoding],
                         max_size=rows * cols * CHANNELS[encoding]))
    return np.frombuffer(raw, np.uint8).reshape(rows, cols, CHANNELS[encoding]).copy(), encoding


# -- the oracles' own tests ---------------------------------------------------------------------

def test_morph_oracle_hand_computed():
    img = np.array([[1, 0, 0], [0, 0, 0], [0, 0, 9]], np.uint8)
    assert morph_oracle(img, "dilate", 3, 3)[:, :, 0].tolist() == [[1, 1, 0], [1, 9, 9], [0, 9, 9]]
    assert morph_oracle(img, "erode", 3, 3)[:, :, 0].tolist() == [[0, 0, 0], [0, 0, 0], [0, 0, 0]]
    row = np.array([[5, 1, 7, 2]], np.uint8)
    # 2 wide, anchor 1: window covers columns c-1 .. c
    assert morph_oracle(row, "dilate", 2, 1)[:, :, 0].tolist() == [[5, 5, 7, 7]]
    assert morph_oracle(row, "erode", 2, 1)[:, :, 0].tolist() == [[5, 1, 1, 2]]


def test_tcpros_frame_layout_by_hand():
    frame = tcpros_frame(image_msg(np.array([[[7]]], np.uint8), "mono8", seq=3, frame_id="f"))
    assert frame == (
        (44).to_bytes(4, "little") + (3).to_bytes(4, "little") + bytes(8)
        + (1).to_bytes(4, "little") + b"f" + (1).to_bytes(4, "little") * 2
        + (5).to_bytes(4, "little") + b"mono8" + b"\x00" + (1).to_bytes(4, "little") * 2 + b"\x07"
    )
