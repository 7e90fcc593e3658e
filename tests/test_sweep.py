"""restitution_map: values on a grid, and a progress bar that ends at the number of points."""

import math

import numpy as np
import pytest

from wavecontact import progress
from wavecontact.studies.sweep import restitution_map

# MODEL.md section 5 (computed independently of this package)
MODEL = {5: 0.93176899, 20: 0.7530132413, 100: 0.646697087}


def test_grid_holds_the_reference_values_in_row_major_order():
    values = restitution_map([0.6, 1.0], [20, 100, math.inf], workers=2, progress=False)
    assert values.shape == (2, 3)
    assert values[0, 0] == pytest.approx(MODEL[20], abs=1e-9)
    assert values[0, 1] == pytest.approx(MODEL[100], abs=1e-9)
    assert values[0, 2] == pytest.approx(0.6, abs=1e-12)  # hard core: epsilon = gamma
    assert np.allclose(values[1], 1.0, atol=1e-9)  # equal rods: elastic


def test_progress_bar_counts_every_point(monkeypatch):
    seen = []

    class Recording(progress.Progress):
        def close(self):
            seen.append((self.done, self.total))
            super().close()

    monkeypatch.setattr(progress, "Progress", Recording)
    restitution_map([0.6], [20, 50, 100, 200, 500], workers=2, progress=False)
    assert seen == [(5, 5)]
