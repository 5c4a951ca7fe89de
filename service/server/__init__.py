"""markerflow's HTTP service: durable labeling jobs over FastAPI (``markerflow serve``)."""
