#!/usr/bin/env python3
"""List-schedule a straight-line SPU block into dual-issue pairs (a hand-tuning aid; see
README.md). Usage: sched.py names.s block.s [POOL] -> prints the scheduled block."""
import os, re, sys
tsv = {}
for line in open(os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../shared/isa/spu-isa.tsv')):
    f = line.rstrip('\n').split('\t')
    if f[0] == 'mnemonic': continue
    tsv.setdefault(f[0], (f[6], int(f[7]) if f[7].isdigit() else 1))
names = {}
for line in open(sys.argv[1]):
    m = re.match(r'\s*\.set\s+(\w+),\s*(\d+)', line)
    if m: names[m.group(1)] = int(m.group(2))
VIRT = {}
def reg(tok):
    tok = tok.strip()
    m = re.match(r'^(-?\w*\()?%(\w+)\)?$', tok)
    if m:
        return VIRT.setdefault(m.group(2), 1000 + len(VIRT))
    m = re.match(r'^\$(\d+)$', tok)
    if m: return int(m.group(1))
    if tok in names: return names[tok]
    m = re.match(r'^-?\w*\((\$?\w+)\)$', tok)
    if m: return reg(m.group(1))
    return None
SRC_RT = {'stqd','stqx','stqa','stqr','brz','brnz','brhz','brhnz','biz','binz','wrch','bi','hbr'}
STORES = {'stqd','stqx','stqa','stqr'}
def expand(lines):
    out = []; i = 0
    while i < len(lines):
        l = lines[i]
        m = re.match(r'\s*\.irp\s+(\w+)\s*,\s*(.*)$', l.split('#')[0])
        if m:
            var, vals = m.group(1), [v.strip() for v in m.group(2).split(',')]
            depth = 1; j = i + 1
            while depth:
                if re.match(r'\s*\.irp', lines[j]): depth += 1
                if re.match(r'\s*\.endr', lines[j]): depth -= 1
                j += 1
            body = lines[i+1:j-1]
            for v in vals:
                out += expand([b.replace('\\' + var, v) for b in body])
            i = j
        else:
            out.append(l); i += 1
    return out
def evalops(line):
    # (expr) register operands and expr(reg) offsets with only numbers left
    def ev(e):
        try: return str(eval(e, {}, dict(names)))
        except Exception: return None
    head, sep, comment = line.partition('#')
    parts = head.split(None, 1)
    if len(parts) < 2: return line
    ops = []
    for o in parts[1].split(','):
        o = o.strip()
        m = re.match(r'^\((.*)\)$', o)
        if m and ev(m.group(1)) is not None:
            o = '$' + ev(m.group(1))
        else:
            m = re.match(r'^(.*)\((\$?\w+)\)$', o)
            if m and m.group(1) and not re.match(r'^-?\d+$', m.group(1)) and ev(m.group(1)) is not None:
                o = ev(m.group(1)) + '(' + m.group(2) + ')'
        ops.append(o)
    lead = line[:len(line) - len(line.lstrip())]
    return lead + parts[0] + ' ' * max(1, 8 - len(parts[0])) + ', '.join(ops) + (('   #' + comment) if sep else '')
insts = []
for raw in [evalops(l) for l in expand(open(sys.argv[2]).read().split('\n'))]:
    line = raw.rstrip('\n')
    if not line.strip() or line.strip().startswith('#'): continue
    barrier = line.lstrip().startswith('!')
    free_store = line.lstrip().startswith('~')
    text = line.lstrip().lstrip('!~').strip()
    after = re.findall(r'@after\s+(%\w+|\$\d+)', text)
    text = re.sub(r'\s*@after\s+(%\w+|\$\d+)', '', text)
    body = text.split('#')[0].strip()
    if body.endswith(':'):
        insts.append(dict(label=body, text=text)); continue
    mn, _, ops = body.partition(' ')
    ops = [o.strip() for o in ops.split(',')] if ops.strip() else []
    regs = [reg(o) for o in ops]
    if mn in SRC_RT or mn.startswith('hbr') or mn in ('br','bra'):
        dst, srcs = [], [r for r in regs if r is not None]
    else:
        dst = [regs[0]] if regs and regs[0] is not None else []
        srcs = [r for r in regs[1:] if r is not None]
    pipe, lat = tsv.get(mn, ('even', 2))
    insts.append(dict(mn=mn, text=text, dst=dst, src=srcs, pipe=pipe, lat=lat, after=[reg(x) for x in after],
                      store=mn in STORES and not free_store, load=mn.startswith('lq'),
                      barrier=barrier or mn.startswith('b') or mn.startswith('hbr')
                      or mn in ('wrch','rdch','stop')))
# dependencies
n = len(insts)
deps = [set() for _ in range(n)]
for i, a in enumerate(insts):
    if 'label' in a: continue
    for j in range(i):
        b = insts[j]
        if 'label' in b: continue
        if set(a['src']) & set(b['dst']) or set(a['dst']) & set(b['src']) or set(a['dst']) & set(b['dst']):
            deps[i].add(j)
        if set(a.get('after', [])) & set(b['dst']):
            deps[i].add(j)
        if a['barrier'] and b['barrier']: deps[i].add(j)
        if a.get('store') and (b.get('store') or b.get('load')): deps[i].add(j)   # stores in order, after earlier loads
        if a.get('store') and b['barrier']: deps[i].add(j)
        if a['barrier']: deps[i].add(j)           # barriers stay after everything earlier
        if b['barrier'] and (a['mn'].startswith('l') or a['mn'] in STORES):  # memory after branch
            deps[i].add(j)
        if b['barrier'] and any(d >= 0 and d not in range(66, 128) for d in a['dst']):
            deps[i].add(j)                          # persistent writes stay below branches
# critical path priority
prio = [0]*n
for i in reversed(range(n)):
    if 'label' in insts[i]: continue
    succ = [k for k in range(i+1, n) if i in deps[k]]
    prio[i] = insts[i]['lat'] + max([prio[k] for k in succ], default=0)
labels = [i for i in range(n) if 'label' in insts[i]]
assert not labels or labels == [0], "labels only at the start"
done = {}; ready_at = {}
POOL_N = len(sys.argv[3].split(',')) if len(sys.argv) > 3 else None
vdefs = [set(r for r in a.get('dst', []) if r >= 1000) for a in insts]
vuses = [set(r for r in a.get('src', []) if r >= 1000) | set(r for r in a.get('after', []) if r is not None and r >= 1000) for a in insts]
remaining_uses = {}
for i, a in enumerate(insts):
    if 'label' in a: continue
    for r in set(a['src']) | set(a['dst']):
        if r >= 1000: remaining_uses[r] = remaining_uses.get(r, 0) + 1
live = set()
def pressure_ok(i):
    if POOL_N is None: return True
    new = vdefs[i] - live
    freed = set(r for r in (vuses[i] | vdefs[i]) if remaining_uses.get(r, 0) == 1 and r in live)
    # the allocator takes the new registers before it frees the last uses, so the pool
    # must hold both; growth keeps a margin so that register-freeing work can always issue
    if len(live) + len(new) > POOL_N:
        return False
    return len(new) <= len(freed) or len(live) + len(new) <= POOL_N - 4
def retire(i):
    for r in set(insts[i]['src']) | set(insts[i]['dst']):
        if r >= 1000:
            remaining_uses[r] -= 1
            if remaining_uses[r] == 0: live.discard(r)
            else: live.add(r)
out = []
if labels: out.append(insts[0]['text'])
remaining = [i for i in range(n) if 'label' not in insts[i]]
t = 0
stuck = 0
def ready(i, t):
    return all(j in done and (done[j][0] + (insts[j]['lat'] if set(insts[i]['src']) & set(insts[j]['dst']) else 1)) <= t for j in deps[i])
while remaining:
    ev = [i for i in remaining if insts[i]['pipe'] == 'even' and ready(i, t) and pressure_ok(i)]
    ev.sort(key=lambda i: (-prio[i], i))
    e = ev[0] if ev else None
    if e is not None: done[e] = (t, 0)
    if e is not None: retire(e)
    od = [i for i in remaining if insts[i]['pipe'] == 'odd' and i != e and ready(i, t)
          and (e is None or e not in deps[i]) and pressure_ok(i)]
    od.sort(key=lambda i: (-prio[i], i))
    o = od[0] if od else None
    if e is not None: del done[e]
    if o is not None: retire(o)
    if e is None and o is None:
        # nothing fits the register pool: take the oldest ready instruction anyway
        blocked = [i for i in remaining if ready(i, t)]
        if blocked and all(not ready(i, t - 1) or True for i in blocked) and stuck > 12:
            i = min(blocked)
            if insts[i]['pipe'] == 'even':
                out.append(insts[i]['text']); out.append('lnop')
            else:
                out.append('nop'); out.append(insts[i]['text'])
            done[i] = (t, 0); remaining.remove(i); retire(i); t += 1; stuck = 0
            continue
        stuck += 1
        t += 1; continue
    stuck = 0
    if e is not None:
        out.append(insts[e]['text']); done[e] = (t, 0); remaining.remove(e)
    else:
        out.append('nop')
    if o is not None:
        out.append(insts[o]['text']); done[o] = (t, 1); remaining.remove(o)
    else:
        out.append('lnop')
    t += 1
# allocate virtual registers in issue order: a register is free after its last read
pool = [int(x) for x in sys.argv[3].split(',')] if len(sys.argv) > 3 else []
if VIRT:
    names_of = {v: k for k, v in VIRT.items()}
    order = [x for x in out]
    def vregs(text):
        return re.findall(r'%(\w+)', text.split('#')[0])
    last = {}
    first = {}
    for k, text in enumerate(order):
        for v in vregs(text):
            first.setdefault(v, k); last[v] = k
    free = list(pool); assign = {}
    for k, text in enumerate(order):
        # free registers whose last use was before this instruction
        for v, l in list(last.items()):
            if v in assign and l < k and assign[v] is not None:
                free.append(assign[v]); assign[v] = None
        for v in vregs(text):
            if v not in assign:
                if not free: sys.exit(f"out of registers at {text}")
                assign[v] = free.pop(0)
    phys = {}
    for k, text in enumerate(order):
        pass
    # second pass: rewrite with a consistent mapping (a name keeps its register for life)
    alive = {}
    free = list(pool); mapping = {}
    for k, text in enumerate(order):
        for v in vregs(text):
            if v not in mapping:
                mapping[v] = free.pop(0)
        order[k] = re.sub(r'%(\w+)', lambda m: '$%d' % mapping[m.group(1)], text)
        for v in set(vregs(text)):
            if last[v] == k:
                free.append(mapping[v])
    out = order
# drop trailing filler
while out and out[-1] in ('nop', 'lnop'): out.pop()
print(f"# scheduled: {t} issue cycles (model), {sum(1 for x in out if x not in ('nop','lnop'))} instructions")
for x in out:
    print(('        ' + x) if not x.endswith(':') else x)
