"""The one CSV and PNG writer (drive_link.link.writers) that traces, replays, captures and report
figures use. Truth: Python's csv reader, numpy's float32 and the PNG signature (ISO/IEC 15948)."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest

from drive_link.link.writers import column_header, csv_text, png_bytes

pytestmark = pytest.mark.unit


def test_csv_reads_back_float32_exactly_under_its_header():
    t = np.arange(4) * 20e-6
    i_p = np.array([1.1, -2.25, 3e-7, np.nan], dtype=np.float32)
    text = csv_text([column_header("t", "s"), column_header("i_p", "A")], [t, i_p])
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == ["t [s]", "i_p [A]"]
    back = np.array([float(r[1]) for r in rows[1:]], dtype=np.float32)
    assert np.array_equal(back, i_p, equal_nan=True)
    assert [float(r[0]) for r in rows[1:]] == pytest.approx(t.tolist(), rel=1e-9)
    assert column_header("hall", "", keep_empty=False) == "hall"
    assert csv_text(["a"], [[1.0]], lineterminator="\n") == "a\n1\n"
    with pytest.raises(ValueError):
        csv_text(["a", "b"], [[1.0]])


def test_png_is_a_png_and_a_pyplot_figure_is_closed():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    data = png_bytes(fig, dpi=50)
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert fig.number not in plt.get_fignums()
