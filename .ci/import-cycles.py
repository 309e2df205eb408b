"""No file of the workspace imports a file that imports it (directly or through others).

Builds the file-level import graph of every crate's src/ (use declarations, crate::, super::,
self:: and child-module paths; a re-export counts as an import of the file it names) and prints
its cycles; exits 1 when there is one. Run from the repository root: python3 .ci/import-cycles.py"""
import os, re, sys, tempfile


def find_cycles(root):
    """The import cycles of the crates under root/crates, and their edges."""
    files = {}  # module path tuple (crate, *mods) -> file
    for crate in sorted(os.listdir(os.path.join(root, 'crates'))):
        src = os.path.join(root, 'crates', crate, 'src')
        if not os.path.isdir(src): continue
        cname = crate.replace('-', '_')
        for dp, _, fs in os.walk(src):
            for f in fs:
                if not f.endswith('.rs'): continue
                p = os.path.join(dp, f)
                rel = os.path.relpath(p, src)[:-3].split(os.sep)
                if rel == ['main'] and os.path.exists(os.path.join(src, 'lib.rs')):
                    # a binary beside a library is a crate of its own, which imports the library
                    files[(cname + '#bin',)] = p
                    continue
                if rel[-1] in ('lib', 'main', 'mod'):
                    rel = rel[:-1]
                files[(cname, *rel)] = p
    def module_of(path_tuple):
        """The longest prefix that is a module file."""
        for k in range(len(path_tuple), 0, -1):
            if path_tuple[:k] in files: return path_tuple[:k]
        return None
    use_re = re.compile(r'^\s*(?:pub(?:\([^)]*\))?\s+)?use\s+([^;]+);', re.S | re.M)
    path_re = re.compile(r'\b((?:crate|super|self)(?:::[A-Za-z_][A-Za-z0-9_]*)+)')
    def expand(tree):
        """Expands `a::{b, c::{d}}` into paths."""
        tree = re.sub(r'\s+', '', tree)
        out = []
        def rec(prefix, t):
            if t.startswith('{') and t.endswith('}'):
                depth, cur, parts = 0, '', []
                for ch in t[1:-1]:
                    if ch == '{': depth += 1
                    if ch == '}': depth -= 1
                    if ch == ',' and depth == 0:
                        parts.append(cur); cur = ''
                    else: cur += ch
                if cur: parts.append(cur)
                for p in parts: rec(prefix, p)
                return
            i = t.find('{')
            if i > 0:
                rec(prefix + t[:i].rstrip(':').split('::'), t[i:])
            else:
                out.append(prefix + [x for x in t.split('::') if x][:])
        rec([], tree)
        return out
    macros = {}  # (crate, name) -> module of the file defining an exported macro
    for mod, p in files.items():
        for name in re.findall(r'#\[macro_export\]\s*macro_rules!\s*(\w+)', open(p).read()):
            macros[(mod[0], name)] = mod
    edges = {}
    for mod, p in files.items():
        text = open(p).read()
        text = re.sub(r'//[^\n]*', '', text)
        text = re.sub(r'r#"(?:.|\n)*?"#', '""', text)
        # char literals first: a '"' would otherwise open a string that swallows the code after it
        text = re.sub(r"'(?:[^'\\\n]|\\.)'", "''", text)
        # \\[\s\S]: an escaped newline (a string continued on the next line) stays in the string
        text = re.sub(r'"(?:[^"\\]|\\[\s\S])*"', '""', text)
        # drop cfg(test) modules declared inline: crude, drop from '#[cfg(test)]\nmod tests {' to end
        m = re.search(r'#\[cfg\(test\)\]\s*mod\s+\w+\s*\{', text)
        if m: text = text[:m.start()]
        is_mod_file = os.path.basename(p) in ('mod.rs', 'lib.rs', 'main.rs')
        here = mod  # module path of this file
        paths = []
        for u in use_re.findall(text):
            u = u.split(' as ')[0]
            paths += expand(u)
        paths += [x.split('::') for x in path_re.findall(text)]
        for x in re.findall(r'\b([a-z_][a-z0-9_]*)::[A-Za-z_]', text):
            if (*here, x) in files:
                paths.append([x, '_item_'])
        for pth in paths:
            if not pth: continue
            head = pth[0]
            if head == 'crate': base = (mod[0],); rest = pth[1:]
            elif head == 'self': base = here; rest = pth[1:]
            elif head == 'super':
                # `super::X` inside an inline module (`mod gpu { use super::X; }`) names an
                # item of this very file: not an import
                if len(pth) > 1 and pth[1] != 'super' and re.search(
                        r'\b(?:struct|enum|fn|trait|type|const|static|mod)\s+%s\b' % re.escape(pth[1]), text):
                    continue
                base = here; rest = pth
                while rest and rest[0] == 'super':
                    base = base[:-1]; rest = rest[1:]
            elif (*here, head) in files:
                base = here; rest = pth
            elif head in ('volux_core', 'volux_io', 'volux_render', 'volux_cli', 'volux_testkit', 'volux_viewer', 'volux_gpu', 'volux_mpi', 'volux_app'):
                base = (head,); rest = pth[1:]
            else: continue
            full = base + tuple(r for r in rest if r not in ('self', '*'))
            target = module_of(full)
            if len(full) == 2 and (full[0], full[1]) in macros:
                target = macros[(full[0], full[1])]
            if target and target != mod:
                edges.setdefault(mod, set()).add(target)
    # cycles: pairs and longer via SCC
    index = {}; low = {}; stack = []; on = set(); sccs = []; counter = [0]
    sys.setrecursionlimit(10000)
    def strong(v):
        index[v] = low[v] = counter[0]; counter[0] += 1; stack.append(v); on.add(v)
        for w in edges.get(v, ()):
            if w not in index: strong(w); low[v] = min(low[v], low[w])
            elif w in on: low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop(); on.discard(w); comp.append(w)
                if w == v: break
            if len(comp) > 1: sccs.append(comp)
    for v in files:
        if v not in index: strong(v)
    out = []
    for c in sccs:
        names = sorted(os.path.relpath(files[m], root) for m in c)
        lines = ['cycle: ' + ' <-> '.join(names)]
        for a in c:
            for b in c:
                if b in edges.get(a, ()):
                    lines.append('    %s -> %s' % (os.path.relpath(files[a], root), os.path.relpath(files[b], root)))
        out.append('\n'.join(lines))
    return out


def self_test():
    """The check finds a planted cycle hidden behind a '"' char literal, and no cycle
    through a binary that imports its own library."""
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, 'crates', 'x', 'src')
        os.makedirs(src)
        files = {
            'lib.rs': 'mod a;\nmod b;\nmod c;\npub use c::C;\npub fn f() {}\n',
            'a.rs': "const Q: char = '\"';\nuse crate::b::B;\npub const S: &str = \"s\";\n",
            'b.rs': 'use crate::a::A;\npub struct B;\n',
            'main.rs': 'use x::f;\nfn main() { f() }\n',
            'c.rs': 'pub struct C;\nmod inner {\n    use super::C;\n}\n',
        }
        for name, text in files.items():
            with open(os.path.join(src, name), 'w') as f:
                f.write(text)
        found = find_cycles(d)
        assert len(found) == 1 and 'a.rs <-> crates/x/src/b.rs' in found[0], found


self_test()
cycles = find_cycles(sys.argv[1] if len(sys.argv) > 1 else '.')
for c in cycles:
    print(c)
print(len(cycles), 'import cycles')
sys.exit(1 if cycles else 0)
