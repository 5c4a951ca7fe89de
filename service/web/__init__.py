"""The service's web page: a jobs list with an upload form, a job page with live progress and
server-drawn plots, all served by the same FastAPI app with no CDN (``pages.mount_web``)."""
