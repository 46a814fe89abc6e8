// llfsm's page: one application for the editor (`llfsm edit`), and, as they move here, the
// live view, the debugger and replay (docs/architecture.md, "The front end").  The server says
// which page it serves in <body data-page>.

import { render } from "preact";
import { connect } from "./api";
import { DebugPage, start as startDebug } from "./debug/Page";
import { App } from "./edit/App";
import { connection, receive } from "./edit/store";
import "./style.css";

const root = document.getElementById("app");
if (root && document.body.dataset.page === "edit") {
  root.replaceChildren();
  render(<App />, root);
  connect(
    receive,
    () => (connection.value = "live"),
    () => (connection.value = "closed"),
  );
} else if (root && document.body.dataset.page === "debug") {
  root.replaceChildren();
  render(<DebugPage />, root);
  startDebug();
}
