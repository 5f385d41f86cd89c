#!/usr/bin/env python3
"""Issue 21's house measurements: per crate, library code only (src/, no main.rs/bin, test
modules and tests_*.rs stripped): pub fn, pub(crate) fn, pub mod, fns over 80 lines,
files over 1000 lines, Result<_, String>."""
import os, re, sys
root = sys.argv[1] if len(sys.argv) > 1 else '.'
LONG = 80
def strip_tests(text):
    # drop `#[cfg(test)] mod x { ... }` blocks
    out, i = [], 0
    lines = text.split('\n')
    skip_depth = None
    depth = 0
    pending = False
    res = []
    for ln in lines:
        if skip_depth is not None:
            depth += ln.count('{') - ln.count('}')
            if depth <= skip_depth:
                skip_depth = None
            continue
        if re.match(r'\s*#\[cfg\(test\)\]', ln):
            pending = True
            continue
        if pending and re.match(r'\s*(pub(\(\w+\))?\s+)?mod\s+\w+\s*\{', ln):
            skip_depth = depth
            depth += ln.count('{') - ln.count('}')
            pending = False
            if depth <= skip_depth: skip_depth = None
            continue
        if pending and re.match(r'\s*(pub(\(\w+\))?\s+)?mod\s+\w+\s*;', ln):
            pending = False
            continue
        pending = False
        depth += ln.count('{') - ln.count('}')
        res.append(ln)
    return '\n'.join(res)
def fns(text):
    lines = text.split('\n')
    out = []
    for i, ln in enumerate(lines):
        m = re.match(r'\s*(pub(\([\w:]+\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)', ln)
        if not m: continue
        # find body start
        depth = 0; started = False
        for j in range(i, len(lines)):
            l = re.sub(r'"(\\.|[^"\\])*"', '""', lines[j])
            l = re.sub(r"'(\\.|[^'\\])'", "''", l)
            l = l.split('//')[0]
            # `[T; N]` in a signature is no end of a declaration
            l = re.sub(r'\[[^\]]*\]', '[]', l)
            if not started and ';' in l and '{' not in l:
                break
            depth += l.count('{') - l.count('}')
            if '{' in l: started = True
            if started and depth <= 0:
                out.append((m.group(6), j - i + 1, i + 1))
                break
    return out
def main():
  for crate in sorted(os.listdir(os.path.join(root, 'crates'))):
    src = os.path.join(root, 'crates', crate, 'src')
    st = dict(pub_fn=0, crate_fn=0, pub_mod=0, long=[], big=[], rs=0)
    for d, _, fs in os.walk(src):
        for f in fs:
            if not f.endswith('.rs'): continue
            p = os.path.join(d, f)
            rel = os.path.relpath(p, src)
            if f == 'main.rs' or rel.startswith('bin/') or f.startswith('tests_') or f == 'tests.rs' or '/tests/' in p: continue
            t = strip_tests(open(p).read())
            n = t.count('\n')
            if n > 1000: st['big'].append((rel, n))
            st['pub_fn'] += len(re.findall(r'^\s*pub\s+(const\s+)?(unsafe\s+)?fn\s', t, re.M))
            st['crate_fn'] += len(re.findall(r'^\s*pub\((crate|super)\)\s+(const\s+)?fn\s', t, re.M))
            st['pub_mod'] += len(re.findall(r'^\s*pub\s+mod\s', t, re.M))
            st['rs'] += len(re.findall(r'Result<[^;{]*,\s*String>', t))
            for name, ln, at in fns(t):
                st.setdefault('all', []).append((ln, f'{rel}:{name}'))
                if ln > LONG:
                    head = '\n'.join(t.split('\n')[max(0, at - 6):at])
                    st['long'].append((ln, f'{rel}:{name}', 'reason' if re.search(r'(?im)^\s*//.*\b(long because|long:|long on purpose|over 80 lines)', head) else ''))
    st['long'].sort(reverse=True)
    print(f"## {crate}: pub fn {st['pub_fn']}, pub(crate|super) fn {st['crate_fn']}, pub mod {st['pub_mod']}, Result<_, String> {st['rs']}, files>1000 {st['big']}")
    top = sorted(st.get('all', []), reverse=True)[:3]
    print("   longest: " + ', '.join(f'{n} {l}' for n, l in top))
    print(f"   fn > {LONG} lines ({len(st['long'])}): " + ', '.join(f'{n} {l}{" ["+r+"]" if r else ""}' for l, n, r in [(b, a, c) for a, b, c in st['long']]))

if __name__ == '__main__':
    main()
