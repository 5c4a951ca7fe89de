"""The subject model (Ringer & Lasenby 2004): which markers ride on which rigid segment, the
ball joints between segments, the marker coordinates in each segment and the limb lengths,
learned from labeled takes of one subject."""
