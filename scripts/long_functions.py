#!/usr/bin/env python3
"""Lists the longest functions and files in the C++ sources (a brace-counting reading of
clang-formatted code: a definition starts with a line whose braces open a body and ends where
they close; lambdas and classes inside count toward the function that holds them).
    python3 scripts/long_functions.py [--top N] [--over LINES] [DIR ...]   (default: src include apps)
"""
import argparse, os, re, sys

SIG = re.compile(r'^(?:[\w:<>,*&~\[\]\s]+?\s)?[*&]?(?P<name>[~\w:]+(?:<[^;{}]*>)?)\s*\((?P<args>.*)$')
SKIP = re.compile(r'^\s*(if|for|while|switch|catch|return|else|do|namespace|struct|class|enum|union|extern|template\s*<[^>]*>\s*(struct|class))\b')


def functions(path):
    lines = open(path, encoding='utf-8', errors='replace').read().split('\n')
    out = []
    i = 0
    while i < len(lines):
        line = lines[i]
        indent = len(line) - len(line.lstrip())
        stripped = line.strip()
        if stripped and not stripped.startswith(('//', '#', '*', '/*')) and not SKIP.match(stripped) and '(' in stripped:
            m = SIG.match(stripped)
            if m and not stripped.endswith(';'):
                # find the opening brace of the body within a few lines
                j, depth_paren, opened = i, 0, False
                text = ''
                while j < len(lines) and j < i + 12:
                    text += lines[j]
                    if '{' in lines[j] and text.count('(') <= text.count(')') + 0:
                        opened = True
                        break
                    if lines[j].rstrip().endswith(';'):
                        break
                    j += 1
                if opened:
                    depth, k = 0, j
                    started = False
                    while k < len(lines):
                        code = re.sub(r'//.*', '', lines[k])
                        code = re.sub(r'"(\\.|[^"\\])*"', '""', code)
                        code = re.sub(r"'(\\.|[^'\\])'", "''", code)
                        depth += code.count('{') - code.count('}')
                        if code.count('{'):
                            started = True
                        if started and depth <= 0:
                            break
                        k += 1
                    n = k - i + 1
                    out.append((n, m.group('name'), i + 1))
                    i = k + 1
                    continue
        i += 1
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--top', type=int, default=15)
    ap.add_argument('--over', type=int, default=0)
    ap.add_argument('dirs', nargs='*', default=['src', 'include', 'apps'])
    a = ap.parse_args()
    funcs, files = [], []
    for d in a.dirs:
        for root, _, names in os.walk(d):
            for f in names:
                if f.endswith(('.cpp', '.h', '.hpp', '.cc')):
                    p = os.path.join(root, f)
                    files.append((sum(1 for _ in open(p, encoding='utf-8', errors='replace')), p))
                    for n, name, line in functions(p):
                        funcs.append((n, f'{p}:{line}', name))
    funcs.sort(reverse=True)
    files.sort(reverse=True)
    sel = [f for f in funcs if f[0] > a.over] if a.over else funcs[:a.top]
    print('longest functions (lines, where, name):')
    for n, where, name in sel:
        print(f'  {n:5d}  {where}  {name}')
    print('longest files (lines):')
    for n, p in (files if a.over == 0 else [f for f in files if f[0] > 600])[:a.top]:
        print(f'  {n:5d}  {p}')


if __name__ == '__main__':
    main()
