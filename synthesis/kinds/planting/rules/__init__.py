"""The kind's own rule families (each imports only casadi, numpy and synthesis.constraints.base)."""
