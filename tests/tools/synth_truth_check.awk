# Truth of a tp-synth scene against its own cameras (tests/tools/tp-synth.cmake): every seen position is
# the projection of the track's X Y Z through truth.cameras; a nan whose projection lies inside the image is a
# point hidden from that view (occlusion). Prints: seen N max error ok|PX hidden N high 0|1 (a Z above 10 m).
# usage: awk -v size=SIZE -f synth_truth_check.awk truth.cameras truth.tracks
FNR==NR { if (!/^#/ && NF==4) { for (c=1;c<=4;c++) P[int(k/3), k%3, c]=$c; k++ } next }
/^#/ { next }
{ N = int(k/3); X=$(2+2*N); Y=$(3+2*N); Z=$(4+2*N); if (Z > zmax) zmax = Z
  for (v=0; v<N; v++) {
    w = P[v,2,1]*X + P[v,2,2]*Y + P[v,2,3]*Z + P[v,2,4]
    x = (P[v,0,1]*X + P[v,0,2]*Y + P[v,0,3]*Z + P[v,0,4]) / w
    y = (P[v,1,1]*X + P[v,1,2]*Y + P[v,1,3]*Z + P[v,1,4]) / w
    if ($(2+2*v) == "nan") { if (x >= 0 && y >= 0 && x <= size-1 && y <= size-1) hidden++ }
    else { e = (x-$(2+2*v))^2 + (y-$(3+2*v))^2; if (e > emax) emax = e; seen++ }
  }
}
END { printf "seen %d max error %s hidden %d high %d\n", seen, (emax < 1e-8 ? "ok" : sqrt(emax)), hidden, (zmax > 10) }
