"""How well spectra measure K: instruments, the σ_v law, strategies, goals, observed data."""
