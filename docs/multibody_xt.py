"""Regenerate the x-t figure of docs/multibody.md: the Hopkinson-bar-like example scene.

Run from the repository root::

    python docs/multibody_xt.py

which runs ``wavecontact solve examples/scenes/hopkinson_bar.toml --elements 200 --xt-plot
docs/figures/multibody_hopkinson_xt.png`` (the fem multi-body loop samples the fields in a second run).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FIGURE = ROOT / "docs" / "figures" / "multibody_hopkinson_xt.png"
COMMAND = ["solve", str(ROOT / "examples" / "scenes" / "hopkinson_bar.toml"), "--elements", "200",
           "--xt-plot", str(FIGURE)]


def main() -> int:
    sys.path.insert(0, str(ROOT))
    from wavecontact.cli import main as cli

    return cli(COMMAND)


if __name__ == "__main__":
    raise SystemExit(main())
