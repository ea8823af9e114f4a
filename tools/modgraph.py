#!/usr/bin/env python3
"""Module import graph of a crate's src/ (top-level modules or all modules), and its cycles.

    python3 tools/modgraph.py btf-render/src [--deep]

Edges come from `use crate::a::…`, `crate::a::…` paths, `use super::…` and `super::x`
paths outside `#[cfg(test)]` modules. Prints the strongly connected components with more
than one member (the import cycles); exit status 1 when there is one.
"""
import os, re, sys

def modules(src):
    mods = {}
    for root, _, files in os.walk(src):
        for f in files:
            if not f.endswith('.rs'):
                continue
            p = os.path.join(root, f)
            rel = os.path.relpath(p, src)[:-3].split(os.sep)
            if rel[-1] in ('mod', 'lib', 'main'):
                rel = rel[:-1]
            mods['::'.join(rel)] = p
    return mods

def strip_tests(text):
    # drop `#[cfg(test)] mod tests { ... }` blocks (brace matching)
    out, i = [], 0
    for m in re.finditer(r'#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{', text):
        if m.start() < i:
            continue
        out.append(text[i:m.start()])
        depth, j = 1, m.end()
        while depth and j < len(text):
            depth += {'{': 1, '}': -1}.get(text[j], 0)
            j += 1
        i = j
    out.append(text[i:])
    return ''.join(out)

def edges(mods, deep):
    names = set(mods)
    E = {m: set() for m in mods}
    for m, p in mods.items():
        text = strip_tests(open(p).read())
        text = re.sub(r'//[^\n]*', '', text)
        parts = m.split('::') if m else []
        is_mod_file = os.path.basename(p) in ('mod.rs', 'lib.rs', 'main.rs')
        here = parts if is_mod_file else parts[:-1]  # the module `super` resolves against
        targets = []
        for t in re.findall(r'crate::((?:\w+::)*\w+)', text):
            targets.append(t.split('::'))
        for t in re.findall(r'\bsuper::((?:\w+::)*\w+)', text):
            base = parts[:-1] if not is_mod_file else parts[:-1]
            targets.append(base + t.split('::'))
        # grouped imports: use crate::{a, b::c}
        for grp in re.findall(r'use\s+crate::\{([^;]*)\}\s*;', text, re.S):
            for item in re.split(r',\s*', grp):
                item = item.strip()
                if item:
                    targets.append(re.split(r'::|\{', item)[0:1])
        for grp in re.findall(r'use\s+super::\{([^;]*)\}\s*;', text, re.S):
            for item in re.split(r',\s*', grp):
                item = item.strip()
                if item:
                    targets.append(parts[:-1] + re.split(r'::|\{', item)[0:1])
        for t in targets:
            # longest prefix that is a module
            best = None
            for k in range(len(t), 0, -1):
                cand = '::'.join(t[:k])
                if cand in names:
                    best = cand
                    break
            if best is None:
                continue
            a, b = m, best
            if not deep:
                a, b = a.split('::')[0], b.split('::')[0]
            if a != b and a and b:
                E.setdefault(a, set()).add(b)
    return E

def sccs(E):
    index, low, stack, on, out, n = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)
    def visit(v):
        index[v] = low[v] = n[0]; n[0] += 1; stack.append(v); on.add(v)
        for w in E.get(v, ()):
            if w not in index:
                visit(w); low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            c = []
            while True:
                w = stack.pop(); on.discard(w); c.append(w)
                if w == v: break
            out.append(c)
    for v in list(E):
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]

if __name__ == '__main__':
    src = sys.argv[1]
    deep = '--deep' in sys.argv
    E = edges(modules(src), deep)
    cyc = sccs(E)
    for c in cyc:
        print('cycle:', ' '.join(sorted(c)))
        for a in sorted(c):
            print('   ', a, '->', ', '.join(sorted(b for b in E[a] if b in c)))
    if not cyc:
        print('no import cycles in', src, '(deep)' if deep else '(top level)')
    sys.exit(1 if cyc else 0)
