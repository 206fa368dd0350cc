// MathJax 2 configuration for pymdownx.arithmatex in generic mode (mkdocs.yml).
//
// MathJax itself is served by the site (assets/mathjax/, copied from the jupyter-server-mathjax
// package by docs/hooks/offline_math.py) and loaded right after this file, which it reads as its
// configuration.  Arithmatex writes inline math as <span class="arithmatex">\(...\)</span> and
// display math as <div class="arithmatex">\[...\]</div>: only those elements are searched.
window.MathJax = {
  tex2jax: {
    inlineMath: [["\\(", "\\)"]],
    displayMath: [["\\[", "\\]"]],
    processEscapes: true,
    processEnvironments: true,
    ignoreClass: ".*|",
    processClass: "arithmatex"
  },
  // The packaged MathJax has the STIX-Web web fonts only (no TeX fonts, no image fonts).
  "HTML-CSS": {
    availableFonts: [],
    preferredFont: null,
    webFont: "STIX-Web",
    imageFont: null
  },
  // The SVG output is not copied into the site: no renderer menu.
  MathMenu: {
    showRenderer: false
  },
  messageStyle: "none"
};

// With Material's instant navigation a new page replaces the content without loading scripts
// again: typeset it once MathJax has started (the first page is typeset by MathJax's startup).
if (typeof document$ !== "undefined") {
  document$.subscribe(function () {
    if (window.MathJax && window.MathJax.Hub && window.MathJax.isReady) {
      window.MathJax.Hub.Queue(["Typeset", window.MathJax.Hub]);
    }
  });
}
