"""Triage (Fig. 2): minimization, replay, the regression suite and the triage pipeline."""
