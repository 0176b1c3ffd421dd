# docs/clusters.md: the paper's clusters accepted; half of cluster A under an affine map accepted as
# affine, with 50 points matched
grep -q '^# verdict: accepted' ab.homography || fail "ab.homography: not accepted"
grep -q '^# verdict: accepted' a-half.homography && grep -q '^# model: affine' a-half.homography ||
  fail "a-half.homography: not accepted as an affine map"
grep -q 'verdict: accepted (50 of 100 points' "$log" || fail "cluster-homog: not the 50 points of half.points matched"
