"""Best view (Jiang, Fels & Little 2008, Sec. III): per object, one camera per frame.

``select_views`` is the sliding-window DP; ``relative_costs`` turns view qualities into
its costs; ``box_quality`` and ``marker_quality`` measure views of boxes and markers.
"""

from formulations.best_view.box_quality import box_quality, box_truncation
from formulations.best_view.costs import relative_costs
from formulations.best_view.marker_quality import marker_quality
from formulations.best_view.selection import select_views

__all__ = ["box_quality", "box_truncation", "marker_quality", "relative_costs", "select_views"]
