#!/usr/bin/env python3
"""Turns a Markdown file's examples into a bash script that runs them as written.

    python3 scripts/doc_blocks.py docs/guide.md OUT_DIR > run.sh

Every ```sh block becomes `run "LINE"` lines (the walkthrough's `run` prints the command, runs
it and times it), in the file's order. A ```toml or ```text block whose first line is
`# NAME` is written to OUT_DIR/NAME, as a reader would save it before the commands that use
it. A block right after a line `<!-- not run: REASON -->` is skipped, with its reason printed
(the commands that need a board). Exits 1 when the file has no block to run.
"""

import re
import shlex
import sys
from pathlib import Path


def blocks(text):
    """(language, lines, skip reason or None) for each fenced block, in order."""
    skip = None
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        marker = re.fullmatch(r"\s*<!--\s*not run:\s*(.*?)\s*-->\s*", line)
        if marker:
            skip = marker.group(1)
        fence = re.fullmatch(r"```(\w*)\s*", line)
        if fence:
            body = []
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append(lines[i])
                i += 1
            yield fence.group(1), body, skip
            skip = None
        elif line.strip() and not marker:
            skip = None
        i += 1


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    source, out = Path(sys.argv[1]), Path(sys.argv[2])
    script = []
    for language, body, skip in blocks(source.read_text()):
        if skip is not None and language in ("sh", "toml", "text"):
            first = next((line for line in body if line.strip()), "")
            script.append(f"printf '\\n$ %s\\n  (not run: %s)\\n' {shlex.quote(first)} {shlex.quote(skip)}")
            continue
        if language == "sh":
            script += [f"run {shlex.quote(line)}" for line in body if line.strip()]
        elif language in ("toml", "text") and body and re.fullmatch(r"# [\w.-]+", body[0]):
            name = body[0][2:]
            (out / name).write_text("\n".join(body) + "\n")
            script.append(f"printf '\\n(wrote %s from the document)\\n' {shlex.quote(name)}")
    if not any(line.startswith("run ") for line in script):
        sys.exit(f"{source}: no ```sh block to run")
    print("\n".join(script))


if __name__ == "__main__":
    main()
