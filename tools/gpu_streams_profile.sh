#!/usr/bin/env bash
# nsys traces of bench_gpu_streams at K = 1 and K = 8 (results/gpu-streams/
# raw/nsys_*), on a device machine. Usage: gpu_streams_profile.sh OUT, from a
# folder holding gpu_streams.tar.xz (tools/gpu_streams.sh prepare),
# nsys_concurrency.py, and dwlib/ with libdw.so.1, libelf.so.1 and
# libbz2.so.1.0 from here: the device machines' nsys is the one Nsight
# Compute ships, whose trace importer needs them and finds none there.
set -u
here=$(cd "$(dirname "$0")" && pwd); out=$1
nsys=$(command -v nsys || echo /opt/nvidia/nsight-compute/2025.3.1/host/target-linux-x64/nsys)
mkdir -p "$here/w" && tar -C "$here/w" -xJf "$here/gpu_streams.tar.xz"
export LD_LIBRARY_PATH=$here/w/lib OMP_WAIT_POLICY=passive
B=$here/w/bin/bench_gpu_streams
importer=$(find / -name 'QdstrmImporter' -type f 2>/dev/null | head -1); echo "importer: $importer"
"$nsys" --version | tee "$out/nsys_version.txt"
for k in 8 1; do
  count=$([ $k = 1 ] && echo 16 || echo 32)
  args=(--lattice=1000 --domains=1000 --count=$count --streams=$k --no-cpu)
  metrics=(--gpu-metrics-devices=0 --gpu-metrics-frequency=10000)
  [ $k = 1 ] && metrics=()
  if [ -f /tmp/k$k.qdstrm ]; then echo "k=$k: trace kept from the last run" >>"$out/nsys_k$k.log"
  elif ! timeout 100 "$nsys" profile -t cuda -s none --cpuctxsw=none "${metrics[@]}" -o /tmp/k$k -f true "$B" "${args[@]}" >"$out/nsys_k$k.log" 2>&1; then
    echo "k=$k with GPU metrics failed; without" | tee -a "$out/nsys_k$k.log"
    timeout 100 "$nsys" profile -t cuda -s none --cpuctxsw=none -o /tmp/k$k -f true "$B" "${args[@]}" >>"$out/nsys_k$k.log" 2>&1
  fi
  grep streams: "$out/nsys_k$k.log"
  if [ ! -f /tmp/k$k.nsys-rep ] && [ -n "$importer" ]; then
    LD_LIBRARY_PATH=$here/dwlib:$LD_LIBRARY_PATH timeout 90 "$importer" -i /tmp/k$k.qdstrm >>"$out/nsys_k$k.log" 2>&1
  fi
  timeout 60 "$nsys" export --type sqlite -o /tmp/k$k.sqlite -f true /tmp/k$k.nsys-rep >>"$out/nsys_k$k.log" 2>&1
  timeout 60 "$nsys" stats -r cuda_gpu_kern_sum,cuda_api_sum -f csv -o "$out/nsys_k$k" /tmp/k$k.sqlite >>"$out/nsys_k$k.log" 2>&1
  echo "== K = $k"; timeout 60 python3 "$here/nsys_concurrency.py" /tmp/k$k.sqlite | tee "$out/nsys_k${k}_concurrency.txt"
done
