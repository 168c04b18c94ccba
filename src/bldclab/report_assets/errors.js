/* bldclab report: records every script error on <html> (data-js-errors, data-js-error-log) before anything else
 * runs, so that a browser test, or a reader, can see that the page worked. Part of bldclab (MIT licence). */
(function () {
  "use strict";
  var log = window.__bldclabErrors = [];
  function record(message) {
    log.push(String(message));
    var root = document.documentElement;
    root.setAttribute("data-js-errors", String(log.length));
    root.setAttribute("data-js-error-log", log.join(" | "));
  }
  window.__bldclabRecord = record;
  window.addEventListener("error", function (e) { record(e.message || "script error"); });
  window.addEventListener("unhandledrejection", function (e) { record("unhandled rejection: " + e.reason); });
  var original = console.error;
  console.error = function () {
    record(Array.prototype.join.call(arguments, " "));
    return original.apply(console, arguments);
  };
}());
