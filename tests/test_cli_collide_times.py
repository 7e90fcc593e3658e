"""wavecontact.cli.collide.duration_text: times in ms or s with 3 significant digits."""

from __future__ import annotations

import pytest

from wavecontact.cli.collide import duration_text


@pytest.mark.parametrize(("seconds", "text"), [
    (3.11e-3, "3.11 ms"), (3.1e-3, "3.10 ms"), (1.36e-4, "0.136 ms"), (0.56, "560 ms"), (0.9994, "999 ms"),
    (0.9996, "1.00 s"), (58.6, "58.6 s"), (99.96, "100 s"), (999.4, "999 s"), (1234.0, "1234 s"),
])
def test_duration_text(seconds, text):
    assert duration_text(seconds) == text
