"""Studies: an experiment's trials analysed (rates, the paper's predictions tested, misconceptions)."""
