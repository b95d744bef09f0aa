"""Artifacts (Fig. 2): crash files and their sidecars, the campaign logs, the corpus manifest."""
