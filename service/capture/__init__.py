"""What a user hands in: the capture, its JSON document, the formulation spec, a recording turned into a capture."""
