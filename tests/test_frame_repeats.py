"""Repeated frames are found by their bytes, exactly: one changed byte anywhere is a new frame, a copy is the same."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from fearguard.perception import SAMPLE_STRIDE, same_bytes


@given(st.integers(1, 40), st.integers(1, 40), st.sampled_from([np.uint8, np.uint16, np.float32]), st.data())
def test_one_changed_byte_anywhere_is_a_new_frame_and_a_copy_is_the_same(h: int, w: int, dtype: type, data: st.DataObject) -> None:
    frame = np.random.default_rng(h * 41 + w).integers(0, 200, (h, w, 3)).astype(dtype)
    assert same_bytes(frame, frame.copy())
    changed = frame.copy()
    raw = changed.reshape(-1).view(np.uint8)
    k = data.draw(st.integers(0, raw.size - 1))
    raw[k] ^= 1
    assert not same_bytes(changed, frame)


def test_a_byte_between_the_sampled_ones_is_still_compared() -> None:
    frame = np.zeros((480, 640, 3), np.uint8)
    changed = frame.copy()
    changed.reshape(-1)[SAMPLE_STRIDE // 2] = 1  # not on the sample grid
    assert not same_bytes(changed, frame)


def test_other_shape_dtype_no_previous_frame_or_python_objects_are_never_the_same() -> None:
    frame = np.zeros((4, 6), np.uint8)
    assert not same_bytes(frame, None)
    assert not same_bytes(frame, np.zeros((6, 4), np.uint8))
    assert not same_bytes(frame, np.zeros((4, 6), np.int8))
    objects = np.array([[1, None]], dtype=object)
    assert not same_bytes(objects, objects.copy())
