import sys,re,collections
# host waits and primitive calls per round from a TETISO_GPU_PROFILE table
rounds=int(sys.argv[2]) if len(sys.argv)>2 else 30
waits={'get','filter','copy_if','count','sync','read_tally','download','upload'}  # exclusive_scan and rank wait through get
c=collections.Counter(); calls=0; w=0
for line in open(sys.argv[1]):
    m=re.match(r'\s*([\d.]+) ms\s+(\d+) calls\s+(\S+) (\S+)',line)
    if not m: continue
    n=int(m.group(2)); what=m.group(3); calls+=n
    if what in waits: w+=n; c[what]+=n
print(f"primitive calls {calls} ({calls/rounds:.1f}/round), host waits {w} ({w/rounds:.1f}/round):", dict(c))
