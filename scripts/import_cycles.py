#!/usr/bin/env python3
"""Finds circles in the import graph among the files of each crate: an edge a -> b when file a
uses a path into file b (crate::, super::, self::, brace groups expanded; edges between a module
and its own submodules are the module tree, not imports, and are left out). Prints each crate's
file and edge counts and its circles (none: []); exits 1 when there is one.

Usage: python3 scripts/import_cycles.py [SRC_DIR ...]   (default: every crate of the workspace)
"""
import os,re,sys
def files_of(root):
    out={}
    for d,_,fs in os.walk(root):
        for f in fs:
            if f.endswith('.rs'):
                rel=os.path.relpath(os.path.join(d,f),root)[:-3].split(os.sep)
                if rel[-1] in('lib','main','mod'): rel=rel[:-1]
                out[tuple(rel)]=os.path.join(d,f)
    return out
def expand(prefix, body):
    res=[]; depth=0; cur=''; parts=[]
    for ch in body:
        if ch=='{': depth+=1
        if ch=='}': depth-=1
        if ch==',' and depth==0: parts.append(cur); cur=''
        else: cur+=ch
    parts.append(cur)
    for p in parts:
        p=p.strip()
        if not p: continue
        m=re.match(r'^((?:\w+::)*)\{(.*)\}$',p,re.S)
        if m: res+=expand(prefix+m.group(1),m.group(2))
        else: res.append(prefix+p)
    return res
found = 0
ROOTS = ["et-core/src", "sim/src", "host/recon/src", "host/learn/src", "host/src", "firmware/src", "python/src"]
for root in sys.argv[1:] or ROOTS:
    F=files_of(root); g={m:set() for m in F}
    for m,f in F.items():
        if m and m[-1]=='tests': continue
        src=open(f).read()
        src=re.split(r'#\[cfg\(test\)\]\s*(#\[[^\n]*\]\s*)*mod tests\s*\{',src)[0]
        src='\n'.join(l for l in src.split('\n') if not l.strip().startswith('//'))
        paths=[]
        for u in re.findall(r'\buse\s+([^;]+);',src,re.S):
            u=re.sub(r'\s+','',u)
            m2=re.match(r'^((?:\w+::)*)\{(.*)\}$',u,re.S)
            paths+= expand(m2.group(1),m2.group(2)) if m2 else [u]
        paths+=re.findall(r'\b(crate::(?:\w+::)*\w+)',src)
        for p in paths:
            p=p.split(' as ')[0]
            seg=p.split('::')
            if seg[0]=='crate': base=(); seg=seg[1:]
            elif seg[0]=='super': base=m[:-1]; seg=seg[1:]
            elif seg[0]=='self': base=m; seg=seg[1:]
            else: continue
            full=base+tuple(s for s in seg if s!='*')
            for n in range(len(full),0,-1):
                t=full[:n]
                if t in F and t!=m:
                    if t==m[:len(t)] or m==t[:len(m)]: break
                    g[m].add(t); break
    idx={};low={};st=[];on=set();c=[0];out=[]
    sys.setrecursionlimit(10000)
    def sc(v):
        idx[v]=low[v]=c[0];c[0]+=1;st.append(v);on.add(v)
        for w in g[v]:
            if w not in idx: sc(w);low[v]=min(low[v],low[w])
            elif w in on: low[v]=min(low[v],idx[w])
        if low[v]==idx[v]:
            comp=[]
            while True:
                w=st.pop();on.discard(w);comp.append(w)
                if w==v:break
            if len(comp)>1: out.append(comp)
    for v in g:
        if v not in idx: sc(v)
    print(root, 'files', len(F), 'edges', sum(len(x) for x in g.values()), 'cycles:', [sorted('::'.join(x) for x in comp) for comp in out])
    found += len(out)
sys.exit(1 if found else 0)
