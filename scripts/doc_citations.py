#!/usr/bin/env python3
"""Checks that every documentation citation resolves: `docs/<file>.md §<section>` (with
optional `item N`, `items N–M`, `quirk N`, `"Title"`, `second table`, `checklist items N–M`)
found in crates/, scripts/, README.md, testdata/README.md, ARCHITECTURE.md and docs/ must
name a file under docs/ that has that numbered section heading (and that item, title or
table inside the section). Citations of the old specification files that lived outside
the repository (the bare names listed in LEGACY, or a bare `spec §N`) are errors too: cite
the docs/ path. `--legacy` accepts them (mapped to their docs/ file) while the code still
uses them. `--list` prints every citation found.

Exit status 1, with one line per citation that does not resolve; 0 otherwise."""
import argparse
import os
import re
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
SELF = os.path.abspath(__file__)

# Old specification names (outside the repository) -> the docs/ file that replaced them.
LEGACY = {
    'imu_utils': 'docs/upstream/imu_utils.md',
    'kalibr_allan': 'docs/upstream/kalibr_allan.md',
    'vio_data_simulation': 'docs/upstream/vio_data_simulation.md',
    'field': 'docs/noise_terms.md',
    'rust_stack': 'docs/formats.md',
}
# A bare `spec §N` meant the specification of the code around it.
BARE_SPEC = [
    ('crates/sim/', 'docs/upstream/vio_data_simulation.md'),
    ('crates/allan_kalibr/src/kalibr/', 'docs/upstream/kalibr_allan.md'),
    ('crates/allan_kalibr/tests/', 'docs/upstream/kalibr_allan.md'),
    ('crates/allan_imu_utils/', 'docs/upstream/imu_utils.md'),
]
SCAN = ['crates', 'scripts', 'docs', 'README.md', 'testdata/README.md', 'ARCHITECTURE.md']
TEXT_EXT = ('.rs', '.py', '.sh', '.md', '.toml', '.yaml', '.yml')

DOC_RE = re.compile(
    r'(?P<path>(?<![\w/.-])docs/[\w/.-]+?\.md)'
    r'|(?P<legacy>(?:(?:\.\./)?shared/specs/|(?<![\w/.-]))(?P<name>' + '|'.join(LEGACY) + r')\.md)'
    r'|(?P<spec>(?<![\w-])[Ss]pec(?:\'s)?(?=\s*§))')
NUM = r'\d+(?:\.\d+)*'
SECTION_RE = re.compile(r'§(' + NUM + r')(?:\s*[–-]\s*§?(' + NUM + r'))?')
ITEMS_RE = re.compile(r'\s*\(?\s*items?\s+(\d+)(?:\s*[–-]\s*(\d+))?\)?')
QUIRK_RE = re.compile(r'\s*(?:/\s*)?quirks?\s+(\d+)(?:\s*[–-]\s*(\d+))?')
TITLE_RE = re.compile(r'\s*"([^"\n]+)"')
TABLE_RE = re.compile(r',?\s*(first|second|third|fourth) table')
CHECKLIST_RE = re.compile(r',\s*checklist items?\s+(\d+)(?:\s*[–-]\s*(\d+))?')
SEP_RE = re.compile(r'\s*(?:,|and|/|;)?\s*(?=§)')
ORDINAL = {'first': 1, 'second': 2, 'third': 3, 'fourth': 4}


class Doc:
    """A markdown file's numbered headings, with each section's lines (subsections included)."""

    def __init__(self, path):
        self.lines = open(path, encoding='utf-8').read().split('\n')
        self.heads = []  # (line index, level, number, title)
        fence = False
        for i, line in enumerate(self.lines):
            if line.startswith('```'):
                fence = not fence
            m = None if fence else re.match(r'(#{1,6})\s+(' + NUM + r')\.?\s+(.*)', line)
            if m:
                self.heads.append((i, len(m.group(1)), m.group(2), m.group(3)))

    def body(self, num):
        for k, (i, level, n, _) in enumerate(self.heads):
            if n == num:
                end = next((j for j, lv, _, _ in self.heads[k + 1:] if lv <= level), len(self.lines))
                return self.lines[i:end]
        return None

    def section_titled(self, word):
        for _, _, n, title in self.heads:
            if word in title.lower():
                return n
        return None


def items_in(body):
    return {int(m.group(1)) for m in (re.match(r'\s*(\d+)\.\s', l) for l in body) if m}


def tables_in(body):
    count, inside = 0, False
    for line in body:
        is_row = line.lstrip().startswith('|')
        count += is_row and not inside
        inside = is_row
    return count


def expand(a, b):
    """Section numbers from a to b (same prefix: every number between; else the two ends)."""
    if not b:
        return [a]
    pa, pb = a.split('.'), b.split('.')
    if len(pa) == len(pb) and pa[:-1] == pb[:-1] and int(pa[-1]) <= int(pb[-1]):
        return ['.'.join(pa[:-1] + [str(k)]) for k in range(int(pa[-1]), int(pb[-1]) + 1)]
    return [a, b]


def strip_comments(path, text):
    if path.endswith('.md'):
        return text
    marker = r'//[/!]?' if path.endswith('.rs') else r'#'
    return '\n'.join(re.sub(r'^\s*(?:' + marker + r')\s?', '', l) for l in text.split('\n'))


def files():
    for entry in SCAN:
        top = os.path.join(ROOT, entry)
        if os.path.isfile(top):
            yield top
        for d, dirs, fs in os.walk(top):
            dirs[:] = [x for x in dirs if x not in ('target', '.git')]
            for f in sorted(fs):
                p = os.path.join(d, f)
                if f.endswith(TEXT_EXT) and os.path.abspath(p) != SELF:
                    yield p


def parse_refs(text, pos):
    """The section references after a document name at `pos`: [(section, quals)], end."""
    refs = []
    p = pos
    while True:
        m = re.compile(r'[`\s]*').match(text, p)
        s = SECTION_RE.match(text, m.end())
        if not s:
            break
        quals = []
        p = s.end()
        while True:
            for kind, rx in (('checklist', CHECKLIST_RE), ('items', ITEMS_RE), ('quirk', QUIRK_RE),
                             ('title', TITLE_RE), ('table', TABLE_RE)):
                q = rx.match(text, p)
                if q:
                    quals.append((kind, q.groups()))
                    p = q.end()
                    break
            else:
                break
        refs.append((expand(s.group(1), s.group(2)), quals))
        sep = SEP_RE.match(text, p)
        if not sep:
            break
        p = sep.end()
    return refs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--legacy', action='store_true',
                    help='accept old spec names and bare "spec §N" (mapped to docs/)')
    ap.add_argument('--list', action='store_true', help='print every citation found')
    args = ap.parse_args()
    docs, bad, found, sources = {}, [], 0, set()

    def doc(rel):
        if rel not in docs:
            p = os.path.join(ROOT, rel)
            docs[rel] = Doc(p) if os.path.isfile(p) else None
        return docs[rel]

    for path in files():
        rel_src = os.path.relpath(path, ROOT)
        text = strip_comments(path, open(path, encoding='utf-8', errors='replace').read())
        for m in DOC_RE.finditer(text):
            line = text.count('\n', 0, m.start()) + 1
            where = f'{rel_src}:{line}'
            problems = []
            if m.group('path'):
                target = m.group('path')
            elif m.group('legacy'):
                target = LEGACY[m.group('name')]
                if not args.legacy:
                    problems.append(f'{m.group("legacy")} is outside the repository: cite {target}')
            else:
                target = next((t for prefix, t in BARE_SPEC if rel_src.startswith(prefix)), None)
                if target is None or not args.legacy:
                    problems.append('bare "spec §": name the document (' + (target or 'docs/…') + ')')
            refs = parse_refs(text, m.end())
            found += 1
            sources.add(rel_src)
            cited = text[m.start():m.end() + 60].split('\n')[0]
            if args.list:
                shown = ' '.join('§' + '–'.join(n) + ''.join(f' {k} {"–".join(x for x in g if x)}'
                                                            for k, g in q) for n, q in refs)
                print(f'{where}: {target} {shown}')
            d = doc(target) if target else None
            if target and d is None:
                problems.append(f'{target} does not exist')
            for nums, quals in refs if d else []:
                for num in nums:
                    body = d.body(num)
                    if body is None:
                        problems.append(f'{target} has no section {num}')
                        continue
                    for kind, g in quals:
                        lo, hi = (int(g[0]), int(g[1] or g[0])) if kind in ('items', 'quirk', 'checklist') else (0, 0)
                        if kind in ('checklist', 'quirk'):
                            # Checklist items and quirks are numbered in the section so titled.
                            n = d.section_titled('checklist' if kind == 'checklist' else 'quirk')
                            have = items_in(d.body(n)) if n else set()
                            missing = [k for k in range(lo, hi + 1) if k not in have]
                            if missing:
                                problems.append(f'{target} has no {kind} item(s) {missing}')
                        elif kind == 'items':
                            missing = [k for k in range(lo, hi + 1) if k not in items_in(body)]
                            if missing:
                                problems.append(f'{target} §{num} has no item(s) {missing}')
                        elif kind == 'title':
                            t = re.escape(g[0].lower())
                            if not any(re.search(r'\*\*\s*' + t, l.lower()) or
                                       (l.startswith('#') and re.search(t, l.lower())) for l in body):
                                problems.append(f'{target} §{num} has no heading or bold label "{g[0]}"')
                        elif kind == 'table' and tables_in(body) < ORDINAL[g[0]]:
                            problems.append(f'{target} §{num} has no {g[0]} table')
            for p in problems:
                bad.append(f'{where}: {cited.strip()!r}: {p}')
    for b in bad:
        print(b)
    if bad:
        print(f'{len(bad)} citation problem(s) among {found} citations in {len(sources)} files',
              file=sys.stderr)
        return 1
    print(f'doc citations: all {found} resolve ({len(sources)} files)', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
