// Keyboard shortcuts of the vinadv viewer: on a pair page f/d/u/c label the pair (FP/DP/UrP/UcP) and n/p move
// to the next/previous pair; on the grid n/p page. Keys typed into a form field are left alone.
(function () {
  "use strict";
  function typing(target) {
    var tag = target && target.tagName;
    return tag === "INPUT" || tag === "SELECT" || tag === "TEXTAREA" || (target && target.isContentEditable);
  }
  function follow(id) {
    var link = document.getElementById(id);
    if (link) { window.location.href = link.href; }
  }
  document.addEventListener("keydown", function (event) {
    if (event.ctrlKey || event.metaKey || event.altKey || typing(event.target)) { return; }
    var key = event.key;
    var form = document.getElementById("label-form");
    if (form) {
      var button = form.querySelector('button[data-key="' + key + '"]');
      if (button) {
        event.preventDefault();
        form.requestSubmit ? form.requestSubmit(button) : button.click();
        return;
      }
    }
    if (key === "n") { follow(form ? "next-pair" : "next-page"); }
    else if (key === "p") { follow(form ? "prev-pair" : "prev-page"); }
  });
})();
