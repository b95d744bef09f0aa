"""Selection (the paper's Fig. 2, seed selection): which input source or mutator to use next."""
