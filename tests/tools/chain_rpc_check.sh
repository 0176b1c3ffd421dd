#!/bin/bash
# tp-chain --rpc-check against truth (issue 51): a tp-synth block of 6 views (2 dates, models biased by
# up to 5 px), its truth tracks (0.1 px of noise added) written as every pair's matches files, and in
# every third track of three views or more its last view moved 3.5 px off, keypoint and all (a wrong
# match whose records agree on the wrong point: the loop closure cannot see it). Prints, without and with the check: the wrong
# views kept, the good views lost, and the largest distance of a kept view from the truth.
# Usage: chain_rpc_check.sh (in a scratch folder; tp-synth and tp-chain on the PATH)
set -eu
tp-synth --out syn --views 6 --dates 2 --size 256 --relief 20 --points 800 --supersample 1 --random-bias 5 --threads 2 >/dev/null 2>&1
# matches files of every pair from the truth; wrong.txt: track and view (1-based) of each wrong view
awk 'BEGIN { srand(1) }
  /^# image[0-9]+: / { k = substr($2, 6) + 0; img[k] = "syn/" $3; size[k] = $4 " " $5; K = k; next }
  /^#/ { next }
  {
    t = $1; n = 0; last = 0
    for (v = 1; v <= K; v++) if ($(2 * v) != "nan") { n++; last = v }
    for (v = 1; v <= K; v++) {
      x[v] = $(2 * v); y[v] = $(2 * v + 1)
      if (x[v] != "nan") { x[v] += 0.12 * (rand() + rand() + rand() - 1.5); y[v] += 0.12 * (rand() + rand() + rand() - 1.5) }
    }
    if (n >= 3 && t % 3 == 0) { x[last] += 2.5; y[last] += 2.5; print t, last > "wrong.txt" }
    for (i = 1; i <= K; i++) for (j = i + 1; j <= K; j++) {
      if (x[i] == "nan" || x[j] == "nan") continue
      f = "pair-" i "-" j ".m"
      if (!(f in started)) {
        started[f] = 1
        printf "# tpkit matches 1\n# image1: %s %s\n# image2: %s %s\n# columns: id1 x1 y1 id2 x2 y2 kx2 ky2\n", img[i], size[i], img[j], size[j] > f
      }
      printf "%d %.6f %.6f %d %.6f %.6f %.6f %.6f\n", t, x[i], y[i], t, x[j], y[j], x[j], y[j] > f
    }
  }' syn/truth.tracks
touch wrong.txt
# the output's tracks against the truth: kp is the truth track id (every keypoint of track t has id t)
score() {
  awk -v label="$2" '
    FILENAME == "wrong.txt" { wrong[$1] = $2; next }
    FILENAME ~ /truth/ && /^#/ { next }
    FILENAME ~ /truth/ { for (v = 1; 2 * v + 1 <= NF - 5; v++) { tx[$1, v] = $(2 * v); ty[$1, v] = $(2 * v + 1) } next }
    /^# columns:/ { for (c = 1; c <= NF - 2; c++) if ($(c + 2) == "kp") ckp = c; next }
    /^# image[0-9]+:/ { K++ }
    /^#/ { next }
    {
      t = $ckp; seen[t] = 1
      for (v = 1; v <= K; v++) {
        if ((t, v) in tx && tx[t, v] != "nan") {
          bad = (t in wrong) && wrong[t] == v
          if ($(2 * v) == "nan") { if (!bad) lost++ }
          else if (bad) kept_wrong++
          else { d = sqrt(($(2 * v) - tx[t, v]) ^ 2 + ($(2 * v + 1) - ty[t, v]) ^ 2); if (d > worst) worst = d }
        }
      }
    }
    END {
      for (t in wrong) n_wrong++
      for (k in tx) { split(k, s, SUBSEP); if (tx[k] != "nan" && !(s[1] in seen) && !((s[1] in wrong) && wrong[s[1]] == s[2])) lost++ }
      printf "%s: %d wrong views, %d kept; good views lost %d; worst kept view %.2f px from truth\n", label, n_wrong, kept_wrong, lost, worst
    }' wrong.txt syn/truth.tracks "$1"
}
tp-chain pair-*.m --min-views 2 -q -o plain.tracks
tp-chain pair-*.m --min-views 2 -q --rpc-check 1 -o checked.tracks
score plain.tracks "no check"
score checked.tracks "rpc check"
grep '^# rpc_check:' checked.tracks
