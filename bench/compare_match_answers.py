#!/usr/bin/python3
"""Compare per-photo answers of two bench_match_eval --pictures folders (JSON per photo).

Usage: compare_match_answers.py OLD_PICTURES_DIR NEW_PICTURES_DIR"""
import json, glob, os, sys, statistics
a_dir, b_dir = sys.argv[1], sys.argv[2]
same = diff = 0
ta, tb, ca, cb, ea, eb = [], [], [], [], [], []
for fa in sorted(glob.glob(os.path.join(a_dir, '*.json'))):
    fb = os.path.join(b_dir, os.path.basename(fa))
    if not os.path.exists(fb):
        continue
    A, B = json.load(open(fa)), json.load(open(fb))
    key = lambda j: (j['spec']['shader'], round(j['similarity'], 6), j['verdict'])
    ka, kb = key(A), key(B)
    exact = A['spec'] == B['spec'] and A['similarity'] == B['similarity']
    ev = lambda j: j.get('evaluation', j.get('target', {}))
    sa, sb = ev(A).get('seconds', 0), ev(B).get('seconds', 0)
    ta.append(sa); tb.append(sb); ea.append(A['evaluations']); eb.append(B['evaluations'])
    if 'cpu_seconds' in ev(A): ca.append(ev(A)['cpu_seconds'])
    if 'cpu_seconds' in ev(B): cb.append(ev(B)['cpu_seconds'])
    flag = 'same' if exact else ('SAME SHADER' if ka[0] == kb[0] else 'DIFFERENT')
    same += exact; diff += not exact
    unref = sum(1 for s in B['starts'] if s.get('finalist') and s.get('refined') is False)
    print(f"{os.path.basename(fa)[:38]:38s} {flag:11s} {ka[0]:>13s} {ka[1]:.4f} | {kb[0]:>13s} {kb[1]:.4f}  "
          f"renders {A['evaluations']:5d} -> {B['evaluations']:5d} unrefined {unref}  wall {sa:5.1f} -> {sb:5.1f}"
          + (f"  cpu {ev(B).get('cpu_seconds', 0):5.1f}" if 'cpu_seconds' in ev(B) else ''))
print(f"identical {same}, differ {diff}")
if not ta:
    sys.exit(f"no per-photo JSON in both {a_dir} and {b_dir}: give two bench_match_eval --pictures folders")
med = statistics.median
print(f"median wall {med(ta):.1f} -> {med(tb):.1f} s; renders {med(ea)} -> {med(eb)}" +
      (f"; cpu {med(ca):.1f}" if ca else '') + (f" -> {med(cb):.1f}" if cb else ''))
