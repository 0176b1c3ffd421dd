# docs/blocks.md: Jacksonville, about 2100 tracks of 2 to 4 views, 2.3 px before and about 0.2 px after
# over the unflagged tracks, about 20 flagged, the points about 0.2 m below the lidar DSM in median
# (NMAD about 0.6 m); the synthetic block's tracks of 2 to 6 views, every image adjusted, a ground point
# per track
n=$(records jax/tracks.tracks)
within "$n" 1900 2300 || fail "jax/tracks.tracks: $n tracks, the page says about 2100"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]*$' jax/tracks.tracks || fail "jax/tracks.tracks: not tracks of 2 to 4 views"
before=$(header rms_before_px jax/adjusted/rpc.residuals) after=$(header rms_after_unflagged_px jax/adjusted/rpc.residuals)
within "$before" 2.1 2.5 && within "$after" 0.15 0.25 || fail "jax: rms $before px before, $after px after; the page says 2.3 and about 0.2"
flagged=$(header flagged_tracks jax/adjusted/rpc.residuals)
within "$flagged" 5 40 || fail "jax: $flagged flagged tracks, the page says about 20"
read -r median nmad < <(awk '!/^#/ && $1 == 0 && $2 == 0 { print $6, $7 }' jax.dz)
within "${median:-9}" -0.35 -0.05 && within "${nmad:-9}" 0.4 0.8 || fail "jax.dz: median ${median:-?} m, NMAD ${nmad:-?} m; the page says about -0.2 and 0.6 m"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]* 5:[0-9]* 6:' block-run/tracks.tracks ||
  fail "block-run/tracks.tracks: $(grep '^# tracks_by_views' block-run/tracks.tracks), tracks of 2 to 6 views expected"
rms=$(header rms_after_unflagged_px block-run/adjusted/rpc.residuals)
within "$rms" 0 0.06 || fail "block-run: rpc-adjust rms after $rms px, above the 0.06 px of a block adjusted to its tie points"
[ "$(records block-run/ground.points)" = "$(records block-run/tracks.tracks)" ] || fail "block-run/ground.points: not a point per track"
