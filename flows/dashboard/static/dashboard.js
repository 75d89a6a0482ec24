// The dashboard's one script: no framework, no outside fetch.
"use strict";

// Live sections: an element with data-refresh="URL" has its content replaced by the HTML fragment at URL every
// data-refresh-s seconds (default 2) for as long as the fragment's root carries data-live="true".
function startRefresh(el) {
  const url = el.dataset.refresh;
  const every = 1000 * parseFloat(el.dataset.refreshS || "2");
  async function tick() {
    try {
      const response = await fetch(url, { headers: { "Accept": "text/html" } });
      if (response.ok) {
        el.innerHTML = await response.text();
        document.dispatchEvent(new CustomEvent("dashboard:refreshed", { detail: el }));
      }
    } catch (err) {
      console.warn("refresh failed", url, err);
    }
    if (el.querySelector("[data-live='true']")) setTimeout(tick, every);
  }
  if (el.querySelector("[data-live='true']")) setTimeout(tick, every);
}

document.addEventListener("DOMContentLoaded", () => {
  document.querySelectorAll("[data-refresh]").forEach(startRefresh);
});
