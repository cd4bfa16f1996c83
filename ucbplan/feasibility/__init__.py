"""Expected signal sizes before observing (paper Sec. 3): K_j, ω̇, Δv_aps, Δv_CM, timing errors."""
