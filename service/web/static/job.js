// Live progress of a queued or running job from its event stream (/jobs/<id>/events, on the
// session cookie: EventSource cannot send an Authorization header). Each finished window moves
// the progress bar and, at most every two seconds, redraws the certificate chart; when the job
// ends the page reloads once to draw what the result holds. While the stream is down (the
// server restarting) the progress line says so; the browser reconnects by itself.
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
  stream.addEventListener("error", function () {
    if (!lost && stream.readyState !== EventSource.CLOSED) {
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
