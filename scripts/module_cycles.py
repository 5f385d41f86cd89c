#!/usr/bin/env python3
"""Module cycles between sibling modules (a module's whole subtree counts as it), per crate:
edges from `crate::a::b`, `super::x` and `self::x` paths in library code (tests stripped
roughly: #[cfg(test)] mod blocks and tests_*.rs files)."""
import os, re, sys, itertools
root = sys.argv[1] if len(sys.argv) > 1 else '.'
sys.path.insert(0, os.path.dirname(__file__))
from measure_house import strip_tests  # noqa
def modpath(src, p):
    rel = os.path.relpath(p, src)[:-3].split('/')
    if rel[-1] in ('mod', 'lib'): rel = rel[:-1]
    return tuple(rel)
for crate in sorted(os.listdir(os.path.join(root, 'crates'))):
    src = os.path.join(root, 'crates', crate, 'src')
    mods = {}
    for d, _, fs in os.walk(src):
        for f in fs:
            if f.endswith('.rs') and f != 'main.rs' and not f.startswith('tests'):
                p = os.path.join(d, f)
                if '/bin/' in p: continue
                mods[modpath(src, p)] = strip_tests(open(p).read())
    known = set(mods)
    # inline `mod x {` blocks are ignored (rare in library code)
    edges = set()
    for m, text in mods.items():
        text = re.sub(r'//.*', '', text)
        for mm in re.finditer(r'\b((?:crate|super|self)(?:::\w+)+)', text):
            parts = mm.group(1).split('::')
            if parts[0] == 'crate': base = (); rest = parts[1:]
            else:
                base = m
                while parts and parts[0] in ('super', 'self'):
                    if parts[0] == 'super': base = base[:-1] if base else base
                    parts = parts[1:]
                rest = parts
            tgt = base
            for x in rest:
                if tgt + (x,) in known: tgt = tgt + (x,)
                else: break
            if tgt != m: edges.add((m, tgt))
    # sibling cycles
    found = set()
    for a, b in edges:
        # common parent
        k = 0
        while k < min(len(a), len(b)) and a[k] == b[k]: k += 1
        if k >= len(a) or k >= len(b): continue  # ancestor/descendant
        sa, sb = a[:k + 1], b[:k + 1]
        back = any(x[:k + 1] == sb and y[:k + 1] == sa for x, y in edges)
        if back:
            key = tuple(sorted(['::'.join(sa), '::'.join(sb)]))
            found.add(key)
            if '-v' in sys.argv: print('   ', '::'.join(a), '->', '::'.join(b))
    print(f"{crate}: {len(found)} sibling cycles: " + ', '.join(f'{x}<->{y}' for x, y in sorted(found)))
