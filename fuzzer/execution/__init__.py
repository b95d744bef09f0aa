"""Execution and oracle (Fig. 2): the session, the two targets, the evaluation of a test
case and the canonicalizing oracle."""
