"""The registered formulations, one file each, behind one contract: a WindowProblem in, a WindowSolution out."""
