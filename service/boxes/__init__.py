"""Boxes in video (MOTChallenge files), tracked per camera by Jiang's window LP."""
