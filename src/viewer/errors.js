// dsreg viewer: records every error of the page (scripts, WebGL, the security policy) where the
// reader and the tests see it: in a box on the page, and in the attributes data-errors (a count)
// and data-status ("loading", "ready" or "error") of <html>. Runs before three.js.
(function () {
  'use strict';
  var root = document.documentElement;
  root.setAttribute('data-status', 'loading');
  root.setAttribute('data-errors', '0');

  function record(message) {
    root.setAttribute('data-errors', String(Number(root.getAttribute('data-errors')) + 1));
    root.setAttribute('data-status', 'error');
    var box = document.getElementById('dsreg-errors');
    if (!box) {
      box = document.createElement('div');
      box.id = 'dsreg-errors';
      document.body.appendChild(box);
    }
    var line = document.createElement('p');
    line.textContent = message;
    box.appendChild(line);
  }

  window.dsregRecordError = record;
  window.addEventListener('error', function (event) {
    var where = event.filename ? ' (line ' + event.lineno + ')' : '';
    record((event.message || 'error') + where);
  });
  window.addEventListener('unhandledrejection', function (event) {
    record('unhandled promise rejection: ' + event.reason);
  });
  document.addEventListener('securitypolicyviolation', function (event) {
    record('the page tried to load ' + event.blockedURI + ' (blocked: it must need nothing from outside)');
  });
})();
