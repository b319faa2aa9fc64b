"""fearguard.vision.medians.median is np.median: the same number for every dtype a frame's arrays have, NaN included."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from fearguard.vision.medians import median

DTYPES = st.sampled_from([np.uint8, np.int64, np.float32, np.float64])


@settings(max_examples=300, deadline=None)
@given(data=st.data(), dtype=DTYPES, shape=hnp.array_shapes(min_dims=1, max_dims=2, min_side=1, max_side=9))
def test_median_equals_numpy(data: st.DataObject, dtype: type, shape: tuple[int, ...]) -> None:
    elements = (st.floats(-1e6, 1e6, width=32) | st.just(float("nan"))) if np.dtype(dtype).kind == "f" else None
    x = data.draw(hnp.arrays(dtype, shape, elements=elements))
    for axis in (None, *range(x.ndim)):
        ours, theirs = np.asarray(median(x, axis)), np.asarray(np.median(x, axis=axis))
        assert ours.shape == theirs.shape
        assert np.array_equal(ours.astype(np.float64), theirs.astype(np.float64), equal_nan=True), (x, axis)


def test_even_count_of_bytes_does_not_wrap() -> None:
    assert float(median(np.array([200, 100], np.uint8))) == 150.0


def test_no_values_is_nan() -> None:
    assert np.isnan(median(np.array([], np.float32)))
    assert np.isnan(median(np.zeros((3, 0), np.float32), axis=1)).all()
