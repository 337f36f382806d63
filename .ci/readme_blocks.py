"""The README's two library code blocks ("Your bearing", "Any plain bearing"), written to files.

    python .ci/readme_blocks.py OUTDIR     -> OUTDIR/your_bearing.py, OUTDIR/any_plain_bearing.py

Standard library only: ``.ci/wheel_check`` runs it with any Python, to run the blocks in a fresh environment
that has the core wheel and nothing else (tests/test_quickstart.py extracts the first block the same way).
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"
#: README section title -> file name
SECTIONS = {"## Your bearing": "your_bearing.py", "## Any plain bearing": "any_plain_bearing.py"}


def block(title: str, text: str | None = None) -> str:
    """The one python block of the README section whose heading starts with ``title``."""
    text = README.read_text() if text is None else text
    start = text.index("\n" + title) + 1
    end = text.find("\n## ", start + 4)
    section = text[start:] if end < 0 else text[start:end]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    if len(blocks) != 1:
        raise SystemExit(f"README section {title!r} should have one python block, found {len(blocks)}")
    return blocks[0]


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    out = Path(argv[0])
    out.mkdir(parents=True, exist_ok=True)
    text = README.read_text()
    for title, name in SECTIONS.items():
        (out / name).write_text(block(title, text))
        print(out / name)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
