# The steady layer's slope test when a bed's passes are correlated (docs/study/layers.md): the
# share of trendless AR(1) series of lag-1 autocorrelation rho whose last n passes the rule's
# per-series limit (the Student quantile at 0.025, n - 2 dof) calls trending. 20,000 series each.
#   python3 docs/study/layers/trend_ar1.py
import random, math
lim={4:6.205,6:3.495,8:2.969}
def tz(y):
    n=len(y); xm=(n-1)/2; ym=sum(y)/n; sxx=sum((i-xm)**2 for i in range(n))
    s=sum((i-xm)*(v-ym) for i,v in enumerate(y))/sxx
    rss=sum((v-ym-s*(i-xm))**2 for i,v in enumerate(y)); se=(rss/(n-2)/sxx)**0.5
    return s/se
random.seed(1)
for rho in (0.0,0.3,0.5):
    for n in (4,6,8):
        hit=0; N=20000
        for _ in range(N):
            x=random.gauss(0,1)/math.sqrt(1-rho*rho) if rho<1 else 0
            y=[]
            for i in range(n+20):
                x=rho*x+random.gauss(0,1); y.append(x)
            if abs(tz(y[-n:]))>lim[n]: hit+=1
        print(f"rho {rho} n {n}: one series false alarm {hit/N:.3f} (nominal 0.025)")
