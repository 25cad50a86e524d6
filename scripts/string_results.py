"""Where product code returns `Result<_, String>` (issue 53 item 4: typed errors through the
layers; a bare String is kept only where a helper builds the message of a positioned error
its caller places, clap's value parsers and the viewer's script runner). Counts per file,
most first, and the total; `#[cfg(test)]` code at a file's end and test files are left out.
Usage: python3 scripts/string_results.py"""
import pathlib
import re

PATTERN = re.compile(r"Result<[^;{\n]*?,\s*String\s*>")
ROOT = pathlib.Path(__file__).resolve().parents[1]
rows = []
files = sorted(ROOT.glob("crates/*/src/**/*.rs")) + sorted(ROOT.glob("src/**/*.rs"))
for path in files:
    if path.name == "tests.rs" or "tests" in path.relative_to(ROOT).parts[:-1]:
        continue
    text = path.read_text(encoding="utf-8")
    text = text.split("#[cfg(test)]")[0]
    n = len(PATTERN.findall(text))
    if n:
        rows.append((n, str(path.relative_to(ROOT))))
for n, name in sorted(rows, key=lambda r: (-r[0], r[1])):
    print(n, name)
print("total", sum(n for n, _ in rows))
