#!/usr/bin/env bash
# Host speed of the shared per-element code: tetiso reduce --device cpu, base vs fan interleaved.
here=$(cd "$(dirname "$0")" && pwd)
nvidia-smi --query-gpu=name --format=csv,noheader; nproc; date -u
for n in base fan; do mkdir -p /tmp/$n; tar -C /tmp/$n -xJf $here/$n.tar.xz; done
export OMP_WAIT_POLICY=passive LD_LIBRARY_PATH=/tmp/base/lib
/tmp/base/bin/tetiso extract --lattice 100 --threads 0 -o /tmp/p100.ply >/dev/null || exit 1
for t in 1 16; do
  reps=$([ $t = 1 ] && echo 3 || echo 5)
  for i in $(seq $reps); do
    for n in base fan; do
      LD_LIBRARY_PATH=/tmp/$n/lib /tmp/$n/bin/tetiso reduce /tmp/p100.ply --device cpu --threads $t --max-error 0.0126262626 -o /tmp/c-$n.ply --report /tmp/c.json >/dev/null
      python3 -c "import json;d=json.load(open('/tmp/c.json'));print('$n threads $t total_s %.3f rounds_s %.3f'%(d['total_seconds'],sum(r['seconds'] for r in d['rounds'])))"
    done
  done
  cmp /tmp/c-base.ply /tmp/c-fan.ply && echo "threads $t: base and fan cmp-identical"
done | tee $OUT/cpu.txt
python3 - <<'PY'
import re,statistics as st,collections
d=collections.defaultdict(list)
for l in open('/tmp/cpu_unused' if False else __import__('os').environ['OUT']+'/cpu.txt'):
    m=re.match(r'(\w+) threads (\d+) total_s ([\d.]+) rounds_s ([\d.]+)',l)
    if m: d[(m.group(1),m.group(2))].append(float(m.group(4)))
for k,v in sorted(d.items()): print(k, 'median rounds_s %.3f'%st.median(v), 'min %.3f'%min(v), len(v))
PY
date -u
