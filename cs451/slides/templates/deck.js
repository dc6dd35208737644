// cs451 slides: typeset the math with the inlined KaTeX, then start reveal.js with the speaker-notes plugin.
// A formula KaTeX cannot read is shown in red and reported on the console with its deck line (the kit's
// tests fail on any console error). window.cs451Deck.ready turns true once reveal.js is ready, and printReady
// once the ?print-pdf layout is done.
(function () {
  "use strict";
  window.cs451Deck = { ready: false, mathErrors: 0 };
  document.querySelectorAll(".math").forEach(function (el) {
    var tex = el.textContent;
    try {
      katex.render(tex, el, { displayMode: el.classList.contains("display"), throwOnError: true, strict: "error" });
    } catch (err) {
      window.cs451Deck.mathErrors += 1;
      el.classList.add("math-error");
      el.textContent = tex;
      console.error("cs451 slides: math at " + el.getAttribute("data-source") + ": " + err.message);
    }
  });
  Reveal.on("ready", function () { window.cs451Deck.ready = true; });
  Reveal.on("pdf-ready", function () { window.cs451Deck.printReady = true; });
  Reveal.initialize({
    hash: true,
    width: 1280,
    height: 720,
    margin: 0.04,
    center: false,
    transition: "none",
    backgroundTransition: "none",
    slideNumber: "c/t",
    controls: true,
    progress: true,
    pdfSeparateFragments: false,
    pdfMaxPagesPerSlide: 1,
    plugins: [RevealNotes]
  });
})();
