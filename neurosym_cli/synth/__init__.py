"""Program synthesis: the oracle dataset, the cached objective, and the MCMC search (paper section 3.4)."""
