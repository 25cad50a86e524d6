"""Function lengths in Rust files (lines from `fn` to its closing brace), longest first:
the house keeps every function of `crates/` and `src/` at 150 lines or fewer (ARCHITECTURE.md).
Usage: python3 scripts/fnlen.py crates src ; MIN=N lists functions at least N lines long
(default 150); the counts over 150 and over 200 go to stderr."""
import os, re, sys
FN = re.compile(r'^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?(extern\s+"C"\s+)?fn\s+(\w+)')
def strip(line):
    # drop string literals and line comments (rough)
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "' '", line)
    return line.split('//')[0]
out = []
for d in sys.argv[1:]:
    for root, _, files in os.walk(d):
        for f in files:
            if not f.endswith('.rs'): continue
            p = os.path.join(root, f)
            lines = open(p, encoding='utf-8', errors='replace').read().split('\n')
            i = 0
            while i < len(lines):
                m = FN.match(lines[i])
                if m:
                    depth = 0; started = False; j = i
                    while j < len(lines):
                        s = strip(lines[j])
                        if not started and ';' in s and '{' not in s: break
                        for ch in s:
                            if ch == '{': depth += 1; started = True
                            elif ch == '}': depth -= 1
                        if started and depth <= 0: break
                        j += 1
                    if started:
                        out.append((j - i + 1, p, i + 1, m.group(7)))
                i += 1
MIN = int(os.environ.get('MIN', 150))
out.sort(reverse=True)
for n, p, l, name in out:
    if n >= MIN: print(n, f'{p}:{l}', name)
print('functions over 150:', sum(1 for o in out if o[0] > 150), ' over 200:', sum(1 for o in out if o[0] > 200), file=sys.stderr)
