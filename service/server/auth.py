"""Bearer tokens: who is asking, so each caller sees only its own jobs.

With no tokens configured (allowed only on a loopback bind, see ``Settings.check_exposure``)
every caller is the one local owner.
"""

from __future__ import annotations

import hmac

from fastapi import Depends, HTTPException, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from service.server.settings import LOCAL_OWNER

bearer = HTTPBearer(auto_error=False, description="A token from the service's [tokens] table.")


def caller(request: Request, credentials: HTTPAuthorizationCredentials | None = Depends(bearer)) -> str:
    """The owner the bearer token names.

    Raises:
        HTTPException: 401 for a missing or unknown token.
    """
    return owner_of(request.app.state.owners, credentials.credentials if credentials else None)


def bearer_token(authorization: str) -> str | None:
    """The token of an ``Authorization: Bearer <token>`` header value, as ``HTTPBearer`` reads it."""
    scheme, _, token = authorization.partition(" ")
    return token.strip() or None if scheme.lower() == "bearer" else None


def owner_of(owners: dict[str, str], token: str | None) -> str:
    """The owner of ``token`` among ``owners`` (secret -> owner); the local owner if there are none.

    Raises:
        HTTPException: 401 for a missing or unknown token.
    """
    if not owners:
        return LOCAL_OWNER
    if token is None:
        raise HTTPException(401, "a bearer token is required (Authorization: Bearer <token>)",
                            headers={"WWW-Authenticate": "Bearer"})
    presented = token.encode()
    # Compare against every secret in constant time: no early exit reveals a prefix match.
    matches = [name for secret, name in owners.items() if hmac.compare_digest(secret.encode(), presented)]
    if not matches:
        raise HTTPException(401, "unknown bearer token", headers={"WWW-Authenticate": "Bearer"})
    return matches[0]
