// Send the token once as a bearer header; the server keeps it in an HttpOnly, SameSite=Strict
// session cookie that the page routes (and their event stream) read.
"use strict";
document.getElementById("sign-in").addEventListener("submit", async function (event) {
  event.preventDefault();
  const message = document.getElementById("sign-in-message");
  const token = document.getElementById("token").value.trim();
  const answer = await fetch("/session", {method: "POST", headers: {"Authorization": "Bearer " + token}});
  if (answer.ok) {
    window.location.reload();
    return;
  }
  const body = await answer.json().catch(function () { return {}; });
  message.textContent = "Not signed in: " + (body.message || answer.statusText);
});
