"""The ``markerflow`` command line: one module per command, sharing how figures and progress are shown."""
