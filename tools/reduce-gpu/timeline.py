import csv,sys,collections
# ncu --csv rows (one metric: gpu__time_duration.sum, ns) -> kernels and GPU-busy time per round
rows=list(csv.DictReader(l for l in open(sys.argv[1]) if l.startswith('"')))
rounds=[];cur=None;prev_fans=False
for r in rows:
    name=r['Kernel Name']; t=float(r['Metric Value'].replace(',',''))
    fans='build_fans' in name
    if fans and not prev_fans:
        cur={'kernels':0,'busy_ns':0.0,'names':collections.Counter()}; rounds.append(cur)
    prev_fans=fans
    if cur is None: continue
    cur['kernels']+=1; cur['busy_ns']+=t
    short=name.split('<')[0].replace('void ','')[-40:]
    cur['names'][short]+=1
print('segment kernels gpu_busy_us  (a segment starts at the first kernel of build_fans; a round is the long segment and the short one after it)')
for i,c in enumerate(rounds): print(i,c['kernels'],round(c['busy_ns']/1e3,1))
print('last full round kernel kinds:',dict(rounds[-2]['names']) if len(rounds)>1 else None)
# the heaviest kernels of the third-last round (long segment + short one), by GPU time
segs=[];cur=None;prev=False
for r in rows:
    name=r['Kernel Name']; t=float(r['Metric Value'].replace(',',''))
    f='build_fans' in name
    if f and not prev: cur=[]; segs.append(cur)
    prev=f
    if cur is not None: cur.append((t,name))
if len(segs)>=6:
    late=segs[-6]+segs[-5]
    agg=collections.defaultdict(lambda:[0,0.0])
    for t,name in late:
        key=name[:160]; agg[key][0]+=1; agg[key][1]+=t
    print('late round: %d kernels, %.1f us'%(len(late),sum(t for t,_ in late)/1e3))
    for key,(n,t) in sorted(agg.items(),key=lambda kv:-kv[1][1])[:25]: print('%8.1f us %3d  %s'%(t/1e3,n,key))
