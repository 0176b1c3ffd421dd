# docs/ground.md: check points within 0.5 m (the page says 0.24 m and 0.17 m), the DEM-held block aligned
# with a median dz of 0
ce=$(header check_after_rmse_h_m gcp-adjusted/accuracy) cv=$(header check_after_rmse_v_m gcp-adjusted/accuracy)
within "$ce" 0.15 0.35 && within "$cv" 0.1 0.3 ||
  fail "gcp-adjusted/accuracy: check points at ${ce:-?} m horizontal, ${cv:-?} m vertical RMSE, the page says 0.24 and 0.17 m"
grep -q '^# shift_enu_m: ' hill.dz || fail "hill.dz: no shift_enu_m line"
dz=$(sed -n 's/^tp-ground: after alignment, dz all: .* dz median \([-0-9.e]*\) m.*/\1/p' "$log" | head -n 1)
within "${dz:-9}" -0.5 0.5 || fail "tp-ground --align: median dz ${dz:-?} m after alignment, the page says 0"
