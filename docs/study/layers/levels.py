# The machine point's numerical checks (docs/study/layers.md): each record's laid passes 7-14 as
# mean ± SE (the passes' scatter over sqrt 8, widened as the steady rule widens a fused bed's for
# the lag-1 autocorrelation of its passes: depth 0.65, packing 0.15), with the lag-1
# autocorrelation its own passes show.
#   python3 docs/study/layers/levels.py docs/study/layers/record/ti64-50um-0.1-gap*.json
import json,sys,math
def series(f):
    d=json.load(open(f)); L=d.get('measured',d)['layers']; P=L['passes'][6:]
    return [p['packing'] for p in P],[p['effective_thickness_m']*1e6 for p in P],[p['covered_fraction'] for p in P]
def ar1(n,rho):
    # The SE factor of a mean of n AR(1) values (src/measure/steady.rs ar1_se_factor).
    g=1+2*sum((1-k/n)*rho**k for k in range(1,n)); return math.sqrt(g*(n-1)/(n-g))
def ms(y,rho=0.0):
    n=len(y); m=sum(y)/n; sd=math.sqrt(sum((v-m)**2 for v in y)/(n-1)); return m,sd/math.sqrt(n)*ar1(n,rho)
def rho(y):
    m=sum(y)/len(y); d=[v-m for v in y]; return sum(a*b for a,b in zip(d,d[1:]))/sum(a*a for a in d)
for f in sys.argv[1:]:
    a,dep,c=series(f)
    (pm,pse),(dm,dse),(cm,cse)=ms(a,0.15),ms(dep,0.65),ms(c)
    print(f"{f.split('/')[-1]:40s} passes 7-14: packing {pm:.3f} ± {pse:.3f}  depth {dm:.1f} ± {dse:.1f} um  covered {cm:.2f} ± {cse:.2f}  rho1 pack {rho(a):+.2f} depth {rho(dep):+.2f}")
print()
for f in sys.argv[1:]:
    d=json.load(open(f)); L=d.get('measured',d)['layers']
    a,dep,c=series(f)
    (pm,pse),(dm,dse),(cm,cse)=ms(a,0.15),ms(dep,0.65),ms(c)
    v=f"steady from {L['steady_from']}" if L['steady'] else f"not steady ({L['steady_from']})"
    print(f"| {f.split('/')[-1][:-5]} | {pm:.3f} ± {pse:.3f} | {dm:.1f} ± {dse:.1f} | {cm:.2f} ± {cse:.2f} | {v} | {d.get('measured',d)['cpu_time']:.0f} |")
