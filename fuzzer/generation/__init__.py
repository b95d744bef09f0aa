"""Generation (the paper's Fig. 2, input generation): fresh inputs made during a campaign."""
