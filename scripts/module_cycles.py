#!/usr/bin/env python3
"""Module cycles per crate, in library code (src/ without main.rs and bin/; test modules and
tests*.rs files stripped).

A module depends on another when its code names it: a path in code (`crate::a::b::f`,
`super::x`, `self::y`), or a `use` tree, grouped imports included (`use super::{a, b::c}`,
nested groups too). A name re-exported by a module's `pub use` counts as the module it comes
from (`crate::Sensor` → the module that defines it). Each dependency is lifted to the two
children of the deepest module the two sides share (a module's whole subtree counts as it),
and the cycles are the strongly connected components of those sibling graphs: `a → b → a` and
`input → rosbag2 → series → input` alike. `-v` prints the edges of each cycle; the exit status
is 1 when a cycle is found, so CI can run it as a check."""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from measure_house import strip_tests  # noqa: E402


def modpath(src, p):
    rel = os.path.relpath(p, src)[:-3].split('/')
    if rel[-1] in ('mod', 'lib'):
        rel = rel[:-1]
    return tuple(rel)


def strip_comments_and_strings(text):
    text = re.sub(r'/\*.*?\*/', '', text, flags=re.S)
    text = re.sub(r'//[^\n]*', '', text)
    text = re.sub(r'"(\\.|[^"\\])*"', '""', text)
    return text


def split_top(s):
    """Splits `a, b::{c, d}, e` at the commas outside braces."""
    parts, depth, cur = [], 0, ''
    for ch in s:
        if ch == '{':
            depth += 1
        elif ch == '}':
            depth -= 1
        if ch == ',' and depth == 0:
            parts.append(cur)
            cur = ''
        else:
            cur += ch
    parts.append(cur)
    return [p.strip() for p in parts if p.strip()]


def expand_use(tree, prefix=()):
    """Every full path of a use tree: `super::{a, b::{c, self}}` → super::a, super::b::c, super::b."""
    tree = tree.strip()
    m = re.match(r'^(.*?)::\s*\{(.*)\}$', tree, flags=re.S)
    if m:
        head = tuple(x for x in m.group(1).replace(' ', '').split('::') if x)
        out = []
        for sub in split_top(m.group(2)):
            out += expand_use(sub, prefix + head)
        return out
    if tree.startswith('{') and tree.endswith('}'):
        out = []
        for sub in split_top(tree[1:-1]):
            out += expand_use(sub, prefix)
        return out
    tree = re.sub(r'\s+as\s+\w+$', '', tree)
    parts = tuple(x for x in tree.replace(' ', '').split('::') if x)
    if parts == ('self',):
        return [prefix]
    if parts and parts[-1] == '*':
        parts = parts[:-1]
    return [prefix + parts]


USE = re.compile(r'\b(pub(?:\([\w:\s]+\))?\s+)?use\s+([^;]+);', re.S)
PATH = re.compile(r'\b((?:crate|super|self)(?:::\w+)+)')


def paths_of(text):
    """(path, is_pub_use) for every path the code names; use trees expanded. An import for
    the docs only (`#[cfg(doc)] use …;`, the targets of intra-doc links) is no dependency."""
    text = re.sub(r'#\[cfg\(doc\)\]\s*(?:pub(?:\([^)]*\))?\s+)?use\s[^;]*;', ' ', text)
    out = []
    for m in USE.finditer(text):
        for p in expand_use(m.group(2)):
            out.append((p, bool(m.group(1))))
    rest = USE.sub(' ', text)
    for m in PATH.finditer(rest):
        out.append((tuple(m.group(1).split('::')), False))
    return out


def base_of(m, parts, known):
    """The module a path starts from, and the rest of it; None for another crate's path.
    A path may start with a child module of the module it is written in (2018 paths:
    `pub use ieee952::Name;` in lib.rs is `crate::ieee952::Name`)."""
    if not parts:
        return None
    if parts[0] == 'crate':
        return (), list(parts[1:])
    if m + (parts[0],) in known:
        return m, list(parts)
    if parts[0] in ('super', 'self'):
        base = m
        parts = list(parts)
        while parts and parts[0] in ('super', 'self'):
            if parts[0] == 'super':
                base = base[:-1]
            parts = parts[1:]
        return base, parts
    return None


def resolve(known, reexports, base, rest, seen=0):
    tgt = base
    for i, x in enumerate(rest):
        if tgt + (x,) in known:
            tgt = tgt + (x,)
            continue
        via = reexports.get((tgt, x))
        if via is not None and seen < 8:
            return resolve(known, reexports, via[0], via[1] + rest[i + 1:], seen + 1)
        break
    return tgt


def sccs(nodes, adj):
    """Tarjan's strongly connected components."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in adj.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(comp)

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


def crate_cycles(src):
    mods = {}
    for d, _, fs in os.walk(src):
        if '/bin' in d[len(src):]:
            continue
        for f in fs:
            if f.endswith('.rs') and f != 'main.rs' and not f.startswith('tests'):
                p = os.path.join(d, f)
                mods[modpath(src, p)] = strip_comments_and_strings(strip_tests(open(p).read()))
    known = set(mods)
    parsed = {m: paths_of(t) for m, t in mods.items()}
    # `pub use path::Name;` in module m: (m, Name) → where Name comes from
    reexports = {}
    for m, ps in parsed.items():
        for p, is_pub in ps:
            if is_pub and len(p) >= 2:
                b = base_of(m, p, known)
                if b is not None and b[1]:
                    reexports[(m, b[1][-1])] = (b[0], b[1][:-1])
    edges = set()
    for m, ps in parsed.items():
        for p, _ in ps:
            b = base_of(m, p, known)
            if b is None:
                continue
            tgt = resolve(known, reexports, b[0], b[1])
            if tgt != m:
                edges.add((m, tgt))
    # lift every edge to the two siblings under the deepest shared parent
    by_parent = {}
    for a, b in edges:
        k = 0
        while k < min(len(a), len(b)) and a[k] == b[k]:
            k += 1
        if k >= len(a) or k >= len(b):
            continue  # one contains the other
        parent = a[:k]
        by_parent.setdefault(parent, {}).setdefault(a[:k + 1], set()).add(b[:k + 1])
    cycles = []
    for parent, adj in by_parent.items():
        nodes = set(adj) | {w for ws in adj.values() for w in ws}
        for comp in sccs(nodes, adj):
            if len(comp) > 1:
                cyc = sorted('::'.join(c) for c in comp)
                detail = sorted(
                    '::'.join(a) + ' -> ' + '::'.join(b)
                    for a, b in edges
                    if len(a) > len(parent) and len(b) > len(parent)
                    and a[:len(parent)] == parent and b[:len(parent)] == parent
                    and a[:len(parent) + 1] in comp and b[:len(parent) + 1] in comp
                    and a[:len(parent) + 1] != b[:len(parent) + 1])
                cycles.append((cyc, detail))
    return sorted(cycles)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith('-')]
    root = args[0] if args else '.'
    total = 0
    for crate in sorted(os.listdir(os.path.join(root, 'crates'))):
        src = os.path.join(root, 'crates', crate, 'src')
        cycles = crate_cycles(src)
        total += len(cycles)
        print(f"{crate}: {len(cycles)} module cycles" +
              (': ' + '; '.join(' <-> '.join(c) for c, _ in cycles) if cycles else ''))
        if '-v' in sys.argv:
            for _, detail in cycles:
                for e in detail:
                    print('   ', e)
    return 1 if total else 0


if __name__ == '__main__':
    sys.exit(main())
