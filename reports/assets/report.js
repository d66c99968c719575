
'use strict';
(function () {
  var dlg = document.getElementById('enlarge');
  if (!dlg || typeof dlg.showModal !== 'function') return;  // no <dialog>: links open the PNG
  var big = dlg.querySelector('img');
  var cap = dlg.querySelector('p');
  document.querySelectorAll('a.enlarge').forEach(function (a) {
    a.addEventListener('click', function (ev) {
      ev.preventDefault();
      big.src = a.getAttribute('href');
      big.alt = a.dataset.title || '';
      cap.textContent = a.dataset.title || '';
      dlg.showModal();
    });
  });
  dlg.addEventListener('click', function () { dlg.close(); });
})();
