#!/usr/bin/env bash
# The results pages are what tools/render_results.py makes of their data and
# prose: every page rendered again from a copy of results/ is the committed
# page, byte for byte, so a page never drifts from its JSON or its page.md.
# A placeholder that names nothing fails with the page.md named and writes
# no page. Skipped (77) without Debian's python3-matplotlib.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
python=/usr/bin/python3
$python -c "import matplotlib" 2>/dev/null || { echo "python3-matplotlib missing"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$root/results" "$work/results"
$python "$root/tools/render_results.py" --results "$work/results" >/dev/null
pages=0
while read -r page; do
    cmp "$root/$page" "$work/$page"
    pages=$((pages + 1))
done < <(cd "$root" && find results -name page.md | sed 's#/page.md$#/README.md#; s#^results/paper-reproduction/README.md$#results/paper-reproduction.md#')
echo "$pages pages are current"
[ "$pages" -ge 10 ]

echo "{{ no_such_name }}" >>"$work/results/fuzz/page.md"
rm "$work/results/fuzz/README.md"
if message=$($python "$root/tools/render_results.py" --results "$work/results" fuzz 2>&1); then
    echo "a placeholder naming nothing was rendered"; exit 1
fi
grep -q "fuzz/page.md: {{ no_such_name }}: NameError" <<<"$message" || { echo "unexpected: $message"; exit 1; }
[ ! -e "$work/results/fuzz/README.md" ]
echo "a placeholder naming nothing fails: $message"
