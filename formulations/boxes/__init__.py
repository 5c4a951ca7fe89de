"""Tracking boxes (people in video) with the window LP: Jiang, Fels & Little (2008), Sec. II-B."""
