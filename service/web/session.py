"""Who is looking at a page: the token kept in a session cookie, accepted by the page routes only.

A browser's ``EventSource`` cannot send an ``Authorization`` header, and a page's links
(downloads, plots) cannot either; so after the user enters a token once, ``POST /session``
(sent with the token as a bearer header, so the body limit's caller check holds) answers a
cookie holding it: ``HttpOnly`` (page scripts never read it), ``SameSite=Strict`` (no other
site's page or link makes the browser send it, so no cross-site request forgery), no expiry
(gone when the browser session ends), ``Secure`` when served over HTTPS. The ``/v1`` API
never reads the cookie: it stays bearer-only. The cookie holds the token itself rather than a
server-side session id, so no session state is shared between server processes, and a token
removed from the configuration stops working on the page at once.
"""

from __future__ import annotations

from fastapi import HTTPException, Request, Response
from starlette.requests import cookie_parser

from service.server.auth import bearer_token, owner_of

COOKIE = "markerflow_token"
PAGE_PREFIXES = ("/jobs", "/session")  # and "/" itself: the paths where the cookie counts


def is_page_path(path: str) -> bool:
    return path == "/" or any(path == prefix or path.startswith(prefix + "/") for prefix in PAGE_PREFIXES)


def presented_token(path: str, authorization: str, cookie_header: str) -> str | None:
    """The bearer token of a request, or on a page path its session cookie."""
    token = bearer_token(authorization)
    if token is None and is_page_path(path):
        token = cookie_parser(cookie_header).get(COOKIE) or None
    return token


def page_owner(request: Request) -> str:
    """The owner whose session cookie this is (the local owner when no tokens are configured).

    Raises:
        HTTPException: 401 without a valid cookie; 403 for a state change from another origin.
    """
    if request.method not in ("GET", "HEAD"):
        same_origin(request)
    return owner_of(request.app.state.owners, request.cookies.get(COOKIE) or None)


def signed_in(request: Request) -> str | None:
    """The page owner, or None where the page must ask for a token."""
    try:
        return owner_of(request.app.state.owners, request.cookies.get(COOKIE) or None)
    except HTTPException:
        return None


def same_origin(request: Request) -> None:
    """Refuse a state change whose ``Origin`` is another site: a second guard beside SameSite,
    for browsers that ignore it and for the token-less loopback mode, which has no cookie.

    Raises:
        HTTPException: 403 naming the origin.
    """
    origin = request.headers.get("origin")
    own = f"{request.url.scheme}://{request.headers.get('host', '')}"
    if origin is not None and origin != own:
        raise HTTPException(403, f"origin {origin} may not change jobs on {own}")


def keep_token(response: Response, request: Request, token: str) -> None:
    response.set_cookie(COOKIE, token, httponly=True, samesite="strict", secure=request.url.scheme == "https", path="/")


def forget_token(response: Response) -> None:
    response.delete_cookie(COOKIE, path="/", httponly=True, samesite="strict")
