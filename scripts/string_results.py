"""Where product code returns `Result<_, String>` (issue 53 item 4: typed errors through the
layers; a bare String is kept only where a helper builds the message of a positioned error
its caller places, clap's value parsers and the viewer's script runner). Counts per file,
most first, and the total; a file's `#[cfg(test)] mod tests` at its end and test files are left out.
Usage: python3 scripts/string_results.py"""
import pathlib
import re

def string_results(text):
    """The `Result<T, String>` types in `text`, brackets balanced (`Result<[u32; 2], String>`
    counts: a pattern that stops at `;` missed it)."""
    found = []
    for m in re.finditer(r"\bResult<", text):
        i, depth, args = m.end(), 1, [""]
        while i < len(text) and depth:
            c = text[i]
            if c in "<([":
                depth += 1
            elif c in ">)]":
                depth -= 1
                if depth == 0:
                    break
            if c == "," and depth == 1:
                args.append("")
            else:
                args[-1] += c
            i += 1
        if len(args) == 2 and args[1].strip() == "String":
            found.append(text[m.start() : i + 1])
    return found


ROOT = pathlib.Path(__file__).resolve().parents[1]
rows = []
files = sorted(ROOT.glob("crates/*/src/**/*.rs")) + sorted(ROOT.glob("src/**/*.rs"))
for path in files:
    if path.name == "tests.rs" or "tests" in path.relative_to(ROOT).parts[:-1]:
        continue
    text = path.read_text(encoding="utf-8")
    text = text.split("#[cfg(test)]\nmod tests")[0]
    n = len(string_results(text))
    if n:
        rows.append((n, str(path.relative_to(ROOT))))
for n, name in sorted(rows, key=lambda r: (-r[0], r[1])):
    print(n, name)
print("total", sum(n for n, _ in rows))
