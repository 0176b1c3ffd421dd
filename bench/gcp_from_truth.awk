# bench/gcp_from_truth.awk: ground control and check points from a tp-synth truth.tracks (tpkit-formats(5)
# gcp), with the tie tracks left over. NCTRL control points (the tracks nearest the scene's four corners
# at 15%/85% of its extent and its centre, seen in the most views), NCHECK check points (evenly spread over
# the other tracks seen in three views or more, else two), every one of them left out of the tie tracks. Noise: N(0,
# SG) metres on each ground coordinate (east, north, up) of a control point (N(0, CSG) on a check point's,
# default 0: a check point is the reference its error is measured against; its noise would be counted as
# the models' error, sqrt(2) CSG horizontally) and N(0, SP) pixels on every measurement, seeded by SEED; BLUNDER metres added to the east of the first control point (a contradicting GCP).
#   awk -v NCTRL=5 -v NCHECK=20 -v SG=0.3 -v SP=0.2 -v SEED=1 -v TIES=ties.tracks \
#       -f bench/gcp_from_truth.awk syn/truth.tracks > points.gcp
# Image paths are written as in truth.tracks (view1.tif ...): rpc-adjust matches them by file name.
function gauss(s,   u, v) { u = rand(); v = rand(); if (u < 1e-300) u = 1e-300; return s * sqrt(-2 * log(u)) * cos(6.283185307179586 * v) }
function clip(x, n) { return x < -0.5 ? -0.5 : (n > 0 && x > n - 0.5 ? n - 0.5 : x) }
BEGIN { if (NCTRL == "") NCTRL = 5; if (NCHECK == "") NCHECK = 20; if (SG == "") SG = 0.3; if (SP == "") SP = 0.2
        if (SEED == "") SEED = 1; if (BLUNDER == "") BLUNDER = 0; if (CSG == "") CSG = 0; srand(SEED); n = 0; nimg = 0 }
/^# image[0-9]+:/ { img[++nimg] = $0; W[nimg] = $4; H[nimg] = $5 }
/^# columns:/ { for (i = 3; i <= NF; ++i) col[$i] = i - 2; head[++nhead] = $0; next }
/^#/ { head[++nhead] = $0; next }
NF > 0 {
  ++n; line[n] = $0; nv = 0
  for (v = 1; v <= nimg; ++v) if ($(col["x" v]) != "nan") ++nv
  views[n] = nv; X[n] = $(col["X"]); Y[n] = $(col["Y"])
  if (n == 1 || X[n] < x0) x0 = X[n]; if (n == 1 || X[n] > x1) x1 = X[n]
  if (n == 1 || Y[n] < y0) y0 = Y[n]; if (n == 1 || Y[n] > y1) y1 = Y[n]
}
END {
  # control points: nearest each anchor among the tracks of the most views (at least 2)
  split("0.15 0.15 0.85 0.85 0.5", ax, " "); split("0.15 0.85 0.15 0.85 0.5", ay, " ")
  maxv = 0; for (t = 1; t <= n; ++t) if (views[t] > maxv) maxv = views[t]
  for (c = 1; c <= NCTRL; ++c) {
    a = (c - 1) % 5 + 1; px = x0 + ax[a] * (x1 - x0); py = y0 + ay[a] * (y1 - y0); best = 0
    for (minv = maxv; minv >= 2 && best == 0; --minv)
      for (t = 1; t <= n; ++t) {
        if (views[t] < minv || used[t]) continue
        d = (X[t] - px) ^ 2 + (Y[t] - py) ^ 2
        if (best == 0 || d < bd) { best = t; bd = d }
      }
    if (best == 0) { print "gcp_from_truth: too few tracks for the control points" > "/dev/stderr"; exit 1 }
    used[best] = 1; role[best] = 0; order[++np] = best
  }
  # check points: among the tracks of 3 views or more if there are enough (a 2-view intersection of
  # a short base measures the measurement noise more than the models), else of 2 or more
  cv = 3; left = 0; for (t = 1; t <= n; ++t) if (!used[t] && views[t] >= cv) ++left
  if (left < NCHECK) { cv = 2; left = 0; for (t = 1; t <= n; ++t) if (!used[t] && views[t] >= cv) ++left }
  step = left / NCHECK; k = 0; next_pick = 0; got = 0
  for (t = 1; t <= n && got < NCHECK; ++t) {
    if (used[t] || views[t] < cv) continue
    if (k >= next_pick) { used[t] = 1; role[t] = 1; order[++np] = t; ++got; next_pick += step }
    ++k
  }
  print "# tpkit gcp 1"
  for (i = 1; i <= nimg; ++i) print img[i]
  print "# source: tp-synth truth; noise added (seed " SEED "): control ground " SG " m, check ground " CSG " m, image " SP " px"
  print "# columns: id role lon lat h sigma_e sigma_n sigma_u image x y sigma_px"
  for (i = 1; i <= np; ++i) {
    t = order[i]; split(line[t], f, " ")
    lat = f[col["lat"]]; rad = 3.141592653589793 / 180
    mlat = 111132.954 - 559.822 * cos(2 * lat * rad); mlon = 111412.84 * cos(lat * rad)
    sg = role[t] ? CSG : SG
    de = gauss(sg) + (i == 1 ? BLUNDER : 0); dn = gauss(sg); du = gauss(sg)
    lon = f[col["lon"]] + de / mlon; la = lat + dn / mlat; h = f[col["h"]] + du
    for (v = 1; v <= nimg; ++v) {
      if (f[col["x" v]] == "nan") continue
      # a measurement lies on its image: the noise clipped at the edge pixels' outer edges
      mx = clip(f[col["x" v]] + gauss(SP), W[v]); my = clip(f[col["y" v]] + gauss(SP), H[v])
      printf "%d %d %.12f %.12f %.4f %s %s %s %d %.4f %.4f %s\n", f[col["track"]], role[t], lon, la, h, SG, SG, SG, v, mx, my, SP
    }
  }
  if (TIES != "") {
    for (i = 1; i <= nhead; ++i) print head[i] > TIES
    for (t = 1; t <= n; ++t) if (!used[t]) print line[t] > TIES
  }
}
