"""The accuracy contract: per-stage figures, tolerances, and the check run at compile time."""
