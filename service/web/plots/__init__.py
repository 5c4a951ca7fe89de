"""The job page's plots, drawn by matplotlib on the server as SVG: no chart library in the page.

Every plot tells its states apart by pattern or marker shape and text, not by colour alone.
"""
