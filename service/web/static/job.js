// Live progress of a queued or running job from its event stream (/jobs/<id>/events, on the
// session cookie: EventSource cannot send an Authorization header). Each finished window moves
// the progress bar and, at most every two seconds, redraws the certificate chart; when the job
// ends the page reloads once to draw what the result holds. While the stream is down (the
// server restarting) the progress line says so; the browser reconnects by itself. A stream the
// server refuses (too many open for the token) is not retried by the browser: the page says so
// and reloads every 10 s instead.
"use strict";
(function () {
  const job = document.getElementById("job");
  const id = job.dataset.job;
  const progress = document.getElementById("progress");
  const progressText = document.getElementById("progress-text");
  const state = document.getElementById("state");
  const chart = document.getElementById("certificate-plot");
  let lastDrawn = 0;
  let pending = null;

  function redrawChart() {
    pending = null;
    lastDrawn = Date.now();
    chart.src = "/jobs/" + id + "/plots/certificate.svg?at=" + lastDrawn;
  }

  const stream = new EventSource("/jobs/" + id + "/events");
  let lost = false;
  let refused = false;
  const RELOAD_MS = 10000;
  stream.addEventListener("error", function () {
    if (stream.readyState === EventSource.CLOSED) {
      // Refused (429: this token's streams are all open elsewhere): the browser does not retry,
      // and the page said "running" for good. Reloading shows the progress as it is then.
      if (!refused) {
        refused = true;
        progressText.textContent += " (live progress refused by the server; reloading every 10 s)";
        setTimeout(function () { window.location.reload(); }, RELOAD_MS);
      }
      return;
    }
    if (!lost) {
      lost = true;
      progressText.textContent += " (connection to the server lost; retrying)";
    }
  });
  stream.addEventListener("open", function () {
    if (lost) {
      lost = false;
      progressText.textContent = progressText.textContent.replace(" (connection to the server lost; retrying)", "");
    }
  });
  stream.addEventListener("window", function (event) {
    const data = JSON.parse(event.data);
    progress.max = data.windows_total;
    progress.value = data.windows_done;
    progressText.textContent = data.windows_done + " of " + data.windows_total + " windows";
    if (pending === null) {
      pending = setTimeout(redrawChart, Math.max(0, 2000 - (Date.now() - lastDrawn)));
    }
  });
  stream.addEventListener("removed", function () {  // removed meanwhile: the reload says not found
    stream.close();
    window.location.reload();
  });
  stream.addEventListener("state", function (event) {
    const data = JSON.parse(event.data);
    state.textContent = data.state;
    state.dataset.state = data.state;
    if (data.state !== "queued" && data.state !== "running") {
      stream.close();
      window.location.reload();
    }
  });
})();
