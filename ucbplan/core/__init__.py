"""The physics core: parameter sets, the phase model u(t), t★ inversion, σ_u/T_valid, smearing.

Pure functions over SI floats; nothing here reads files, prints or imports a higher layer.
"""
