"""Every drawing of a machine, from the text alone or from the description a run publishes.

- `text`: a guard as an arrow's label (one line, cut short);
- `mermaid`, `dot`: a machine directory's diagram as Mermaid or Graphviz text (`llfsm graph`);
- `description`: what a published description (llfsm.ros.control.description) must be before
  it is drawn: it may come from any peer on a DDS domain;
- `layout`, `svg`: a description laid out here (no Graphviz) and drawn as SVG, with the current
  state marked, the states layout.yaml places where it places them (the web view's and the
  editor's diagrams, `llfsm graph --format svg`); `png`: that SVG drawn into pixels with Pillow
  (`--format png`).

Nothing here imports the web view or the command line: they import this.
"""
