"""Running learner executables (processes, the sandbox) and observing them (probes)."""
