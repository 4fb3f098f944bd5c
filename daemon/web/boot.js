// boot.js — loaded first, as a classic script: records every JavaScript
// error (uncaught, unhandled rejections, console.error) into #js-errors
// and the body's data-errors count, so that a test reading the DOM, and a
// user opening the panel, sees what broke.
(function () {
  function record(msg) {
    var box = document.getElementById('js-errors');
    if (box) {
      box.hidden = false;
      box.textContent += msg + '\n';
    }
    var n = Number(document.body.getAttribute('data-errors') || 0) + 1;
    document.body.setAttribute('data-errors', String(n));
  }
  window.addEventListener('error', function (e) {
    record('error: ' + (e.message || e.type) +
           (e.filename ? ' (' + e.filename + ':' + e.lineno + ')' : ''));
  });
  window.addEventListener('unhandledrejection', function (e) {
    var r = e.reason;
    if (r && r.auth) return; // a 401: the token prompt says it
    record('unhandled rejection: ' + (r && r.stack ? r.stack : r));
  });
  var orig = console.error;
  console.error = function () {
    record('console.error: ' + Array.prototype.join.call(arguments, ' '));
    return orig.apply(console, arguments);
  };
})();
