"""What relaxed formulations share: the window LP as sparse matrices, column pricing,
components, Viterbi, rounding and certifying."""
