# docs/blocks.md: Jacksonville, about 2700 tracks of 2 to 4 views, 0.9 px before and about 0.18 px after
# over the unflagged tracks, about 15 flagged, the points about 0.5 m below the lidar DSM in median
# (NMAD about 0.65 m); the synthetic block's tracks of 2 to 6 views, every image adjusted, a ground point
# per track
n=$(records jax/tracks.tracks)
within "$n" 2450 2950 || fail "jax/tracks.tracks: $n tracks, the page says about 2700"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]*$' jax/tracks.tracks || fail "jax/tracks.tracks: not tracks of 2 to 4 views"
before=$(header rms_before_px jax/adjusted/rpc.residuals) after=$(header rms_after_unflagged_px jax/adjusted/rpc.residuals)
within "$before" 0.75 1.05 && within "$after" 0.14 0.22 || fail "jax: rms $before px before, $after px after; the page says 0.9 and about 0.18"
flagged=$(header flagged_tracks jax/adjusted/rpc.residuals)
within "$flagged" 5 30 || fail "jax: $flagged flagged tracks, the page says about 15"
read -r median nmad < <(awk '!/^#/ && $1 == 0 && $2 == 0 { print $6, $7 }' jax.dz)
within "${median:-9}" -0.65 -0.35 && within "${nmad:-9}" 0.5 0.8 || fail "jax.dz: median ${median:-?} m, NMAD ${nmad:-?} m; the page says about -0.5 and 0.65 m"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]* 5:[0-9]* 6:' block-run/tracks.tracks ||
  fail "block-run/tracks.tracks: $(grep '^# tracks_by_views' block-run/tracks.tracks), tracks of 2 to 6 views expected"
rms=$(header rms_after_unflagged_px block-run/adjusted/rpc.residuals)
within "$rms" 0 0.06 || fail "block-run: rpc-adjust rms after $rms px, above the 0.06 px of a block adjusted to its tie points"
[ "$(records block-run/ground.points)" = "$(records block-run/tracks.tracks)" ] || fail "block-run/ground.points: not a point per track"
