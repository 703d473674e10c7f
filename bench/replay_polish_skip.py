#!/usr/bin/python3
"""Replay of the polish skip rule (search/match.cpp kPolishGain, session 14) on per-target match JSONs
written by the code before it (bench_match_eval --pictures DIR): which polishes of non-deterministic
finalists on clean patterns it would skip, their polish seconds, and kept polishes it would lose.
Usage: bench/replay_polish_skip.py GAIN DIR [DIR...]  (approximate: candidates = the finalists at
256 px plus kept polishes in finalist order; pixel-exact and visibly-other rules left out)"""
import json,glob,sys,math
G=float(sys.argv[1])
dec=lambda S,P: math.log(max(S,1e-9))+0.25*math.log(max(P,1e-9))
def score(S,P): return 1e6+S if S>=0.75 else dec(S,P)
tot=0; saved=0; lost=[]; skipped=0; n=0
for d in sys.argv[2:]:
  for f in sorted(glob.glob(d+'/*.json')):
    j=json.load(open(f))
    if not j.get('pattern'): continue
    fin=[s for s in j['starts'] if s.get('finalist')]
    cands=[(s['refined_similarity'],s['selection_probability']) for s in fin]
    for s in fin:
        p=s.get('polish')
        if not p or p.get('deterministic') is not False or 'skipped' in p: continue
        n+=1
        sec=sum(p.get('seconds',{}).values()); tot+=sec
        S=s['refined_similarity']; P=s['selection_probability']; reach=min(1,S*G)
        best=max(score(*c) for c in cands); least=min(c[0] for c in cands)
        could = reach>=0.75 or dec(reach,P)>best or reach>2.25*least
        if not could:
            skipped+=1; saved+=sec
            if p.get('kept'): lost.append((f.split('/')[-1], s['shader'], 'kept', j['spec']['shader']==s['shader']))
        elif p.get('kept'):
            cands.append((max(p.get('similarity',0),p.get('recoloured_similarity',0)),P))
print('G=%.2f: %d of %d non-deterministic polishes skipped, %.0f of %.0f polish seconds; kept polishes lost: %s'%(G,skipped,n,saved,tot,lost))
