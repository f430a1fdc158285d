"""Many runs of one case: sweeps, the optimum, calibration, reports and plots."""
