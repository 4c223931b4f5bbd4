#!/usr/bin/env python3
"""The #include "..." lines against the dependencies the folder READMEs state.

usage: include_deps.py SOURCE_DIR

Each folder's README says what it may depend on (common/README.md, sph_node/README.md "Rooms",
dem_node/README.md "Rooms", coordinator/README.md); ALLOW below is that table. Headers are
included by name (every folder is on the include path), so a header is mapped to the folder that
holds it. Exit 0 when every include is allowed, 1 with one line per violation.
"""
import collections
import os
import re
import sys

root = sys.argv[1]
# every folder of the components that holds sources; one missing from ALLOW below fails the test
dirs=sorted(os.path.relpath(dp,root) for top in ('common','sph_node','dem_node','coordinator')
            for dp,_,fs in os.walk(os.path.join(root,top)) if any(f.endswith(('.c','.h')) for f in fs))
hdr={}
for d in dirs:
    for f in os.listdir(os.path.join(root,d)):
        if f.endswith('.h'): hdr[f]=d
C='common/'
allow={
'common/scene':[], 'common/geometry':['common/scene'], 'common/memory':[], 'common/kernels':[],
'common/io':['common/scene','common/geometry','common/kernels'],
'common/protocol':['common/scene','common/io','LCM'],
'sph_node':['sph_node/*','common/*','LCM'],
'sph_node/node':['sph_node','sph_node/*','common/*','LCM'],
'sph_node/particles':['common/*'],
'sph_node/fluid':['sph_node/particles','sph_node/soil','sph_node/coupling','common/*'],
'sph_node/soil':['sph_node/particles','common/*'],
'sph_node/coupling':['sph_node/particles','common/*','sph_node/fluid/sph_riemann.h'],
'sph_node/probes':['sph_node/particles','sph_node/fluid','common/*'],
'sph_node/inflow':['sph_node/particles','sph_node/fluid','common/*'],
'dem_node':['dem_node/engines','common/*','LCM'],
'dem_node/engines':['dem_node/contact','common/*','dem_node/engines/spheropoly','dem_node/engines/lammps'],
'dem_node/engines/spheropoly':['dem_node/contact','common/*','dem_node/engines'],
'dem_node/engines/lammps':['dem_node/contact','common/*','dem_node/engines'],
'dem_node/contact':['common/*'],
'coordinator':['common/*','LCM','coordinator/check','dem_node','dem_node/engines','sph_node','sph_node/inflow'],
'coordinator/check':['common/*'],
'coordinator/run':['coordinator','common/*','LCM','dem_node','sph_node'],
}
lcm=set('lahar_'+f[:-4]+'.h' for f in os.listdir(os.path.join(root,'lcm_types')) if f.endswith('.lcm'))
def ok(d,t,h=None):
    if t==d: return True
    if h and t+'/'+h in allow[d]: return True
    for a in allow[d]:
        if a=='*': return True
        if a.endswith('/*') and t.startswith(a[:-1]): return True
        if a==t: return True
    return False
bad=collections.defaultdict(set)
for d in dirs:
    if d not in allow:
        bad[d].add(f"{d}: a folder whose dependencies no README states (add it to ALLOW and to its README)")
        continue
    for f in sorted(os.listdir(os.path.join(root,d))):
        if not f.endswith(('.c','.h')): continue
        for i,l in enumerate(open(os.path.join(root,d,f)),1):
            m=re.match(r'\s*#\s*include\s*"([^"]+)"',l)
            if not m: continue
            h=os.path.basename(m.group(1))
            if h in lcm or h == 'lahar_lcm_types.h' or (h.startswith('lahar_') and h.endswith('_t.h')): t='LCM'
            elif h in hdr: t=hdr[h]
            else: t='?'+h
            if t=='LCM':
                if not ok(d,'LCM'): bad[d].add(f"{d}/{f}:{i}: {h} (LCM)")
                continue
            if t.startswith('?'): bad[d].add(f"{d}/{f}:{i}: unknown {h}"); continue
            if not ok(d,t,h): bad[d].add(f"{d}/{f}:{i}: {h} ({t})")
n = 0
for d in bad:
    for x in sorted(bad[d]):
        print(x)
        n += 1
print(f"include_deps: {len(dirs)} folders, {n} includes against the READMEs' dependencies")
sys.exit(1 if n else 0)
