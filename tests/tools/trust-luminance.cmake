# Issue 51, item 1: a multi-band image is matched on a grey rendering of all its bands by default.
set(_jax "$SHARED/data/wv3-jacksonville")
# An RGB pair (WorldView-3, Jacksonville) is matched on its luminance, named in the detector lines, and
# finds clearly more matches than band 1 alone (1265 against 973 when written); the keypoint cache keys
# on the rendering: band 1's keypoints are detected again, not taken from the luminance's, and a second
# luminance run reads its own.
tpkit_tool_test(tp-match.rgb-luminance
  COMMAND "A=${_jax}/JAX_068_001_RGB.tif B=${_jax}/JAX_068_003_RGB.tif @SEMI@ tp-match $A $B --cache kp --no-refine --threads 2 -q -o y.m && tp-match $A $B --cache kp --no-refine --threads 2 --band 1 -o b.m 2> b.err && ! grep -q cached b.err && grep -q '^# detector1: sift tpkit-4 band=1 ' b.m && grep -q '^# detector2: sift tpkit-4 luminance=0.299R+0.587G+0.114B ' y.m && test $(grep -vc '^#' y.m) -gt $(( $(grep -vc '^#' b.m) * 11 / 10 )) && tp-match $A $B --cache kp --no-refine --threads 2 -o y2.m && cmp y.m y2.m"
  STDERR_MATCH "keypoints [0-9]+ \\(cached\\) / [0-9]+ \\(cached\\)"
  CHECK_FILE y.m FILE_MATCH "# detector1: sift tpkit-4 luminance=0.299R\\+0.587G\\+0.114B tile=")
