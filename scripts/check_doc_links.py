#!/usr/bin/env python3
# Every relative link and image in README.md and docs/**/*.md must point at an existing file,
# and a #fragment at a heading of that file (GitHub's heading slugs). Links inside fenced code
# blocks and URLs (http:, https:, mailto:) are not checked. Prints one line per broken link
# and exits 1 if there is any (ctest runs it as Docs.LinksResolve).
#   python3 scripts/check_doc_links.py [REPOSITORY_ROOT]
import re, os, sys, glob
root = sys.argv[1] if len(sys.argv) > 1 else "."
files = [os.path.join(root, "README.md")] + glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True)
def slugs(path):
    out = set(); counts = {}
    in_code = False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"): in_code = not in_code
        if in_code: continue
        m = re.match(r"^(#{1,6})\s+(.*?)\s*$", line)
        if not m: continue
        t = m.group(2).lower()
        t = re.sub(r"[^\w\- ]", "", t)
        t = t.replace(" ", "-")
        n = counts.get(t, 0); counts[t] = n + 1
        out.add(t if n == 0 else f"{t}-{n}")
    return out
bad = 0
link = re.compile(r"\]\(([^)\s]+)\)")
for f in files:
    text = open(f, encoding="utf-8").read()
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    for target in link.findall(text):
        if re.match(r"^[a-z]+:", target): continue
        path, _, frag = target.partition("#")
        full = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
        if not os.path.exists(full):
            print(f"{f}: missing {target}"); bad += 1; continue
        if frag and full.endswith(".md") and frag not in slugs(full):
            print(f"{f}: no heading #{frag} in {path or 'itself'}"); bad += 1
print(f"{len(files)} files checked, {bad} broken")
sys.exit(1 if bad else 0)
