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
print('round kernels gpu_busy_us')
for i,c in enumerate(rounds): print(i,c['kernels'],round(c['busy_ns']/1e3,1))
print('last full round kernel kinds:',dict(rounds[-2]['names']) if len(rounds)>1 else None)
