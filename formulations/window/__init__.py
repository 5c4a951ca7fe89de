"""The window problem (Jiang et al. 2008, Sec. II-B): candidates in, a layered network with costs out, and what a solution is."""
