"""Third-party worlds fearguard drives in closed loop (each imports its simulator lazily)."""
