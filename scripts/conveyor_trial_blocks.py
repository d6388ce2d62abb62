#!/usr/bin/env python3
"""Block series of a conveyor run -> transient (MSER), steady MFR, batch-means SE, lag-1 ACF, trend."""
import sys, re, math
def analyse(path):
    hdr = open(path.replace("out.txt","in.liggghts")).readline()
    kv = dict(re.findall(r"(\w+)=([\d.e+-]+)", hdr))
    D=float(kv["D"])*1e-3; gap=float(kv["gap"])*1e-3; v=float(kv["v"]); depth=float(kv["depth"]); bs=int(kv["block"])
    dt=float(re.search(r"timestep ([\d.e+-]+)", open(path.replace("out.txt","in.liggghts")).read()).group(1))
    rows=[l.split() for l in open(path) if l.startswith("BLOCK")]
    tr=[float(r[11]) if len(r)>11 else 0.0 for r in rows]
    m=[float(r[5])+tr[i]-(tr[i-1] if i else 0.0) for i,r in enumerate(rows)]; heap=[int(r[7]) for r in rows]
    ideal=7980*depth*gap*v*dt*bs
    y=[x/ideal for x in m]
    n=len(y)
    # MSER: truncation d minimising var(y[d:])/(n-d), d <= n/2
    best=None
    for d in range(0,n//2+1):
        t=y[d:]; k=len(t); mu=sum(t)/k; s2=sum((x-mu)**2 for x in t)/k
        stat=s2/k
        if best is None or stat<best[0]: best=(stat,d)
    d=best[1]; t=y[d:]; k=len(t); mu=sum(t)/k
    var=sum((x-mu)**2 for x in t)/(k-1)
    acf1=sum((t[i]-mu)*(t[i+1]-mu) for i in range(k-1))/((k-1)*var) if var>0 else 0
    se_naive=math.sqrt(var/k)
    # batch means with b blocks per batch
    out={}
    for b in (1,2,4):
        nb=k//b; bm=[sum(t[i*b:(i+1)*b])/b for i in range(nb)]
        mb=sum(bm)/nb; out[b]=math.sqrt(sum((x-mb)**2 for x in bm)/(nb-1)/nb) if nb>1 else float('nan')
    # trend: OLS slope over the window, SE from residuals
    xs=list(range(k)); xm=sum(xs)/k
    sxx=sum((x-xm)**2 for x in xs); slope=sum((xs[i]-xm)*(t[i]-mu) for i in range(k))/sxx
    res=[t[i]-mu-slope*(xs[i]-xm) for i in range(k)]
    se_slope=math.sqrt(sum(r*r for r in res)/(k-2)/sxx)
    q=k//4; drift=(sum(t[-q:])/q-sum(t[:q])/q)/mu if mu>0 else 0
    return dict(v=v,gap=gap,D=D,n=n,trunc=d,trunc_D=d*v*dt*bs/D,mfr=mu,se1=out[1],se2=out[2],se4=out[4],acf1=acf1,
                trend_t=slope/se_slope if se_slope>0 else 0,drift=drift,heap0=heap[d],heap1=heap[-1],
                win_D=k*v*dt*bs/D)
if __name__=="__main__":
    print("run v gap/D trunc(blocks,D) MFR SE(b=1,2,4) rel_se acf1 trend_t drift_q4-q1 heap0->1 window_D")
    for p in sys.argv[1:]:
        r=analyse(p)
        print(f"{p} {r['v']} {r['gap']/r['D']:.2f} {r['trunc']},{r['trunc_D']:.0f} {r['mfr']:.4f} {r['se1']:.4f},{r['se2']:.4f},{r['se4']:.4f} {r['se2']/r['mfr'] if r['mfr'] else 0:.3f} {r['acf1']:+.2f} {r['trend_t']:+.2f} {r['drift']:+.3f} {r['heap0']}->{r['heap1']} {r['win_D']:.0f}")
