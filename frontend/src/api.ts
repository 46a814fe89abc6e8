// The page's way to its server (docs/edit.md, docs/view.md): JSON POSTs and one WebSocket.
// A token (any address but loopback) comes in the page's URL and goes with every request.

export const token: string | null = new URLSearchParams(location.search).get("token");

export interface Answer {
  success: boolean;
  message: string;
  [key: string]: unknown;
}

export async function post<T extends Answer = Answer>(path: string, body: unknown): Promise<T> {
  const headers: Record<string, string> = { "Content-Type": "application/json" };
  if (token) headers["X-LLFSM-Token"] = token;
  try {
    const r = await fetch(path, { method: "POST", headers, body: JSON.stringify(body), credentials: "same-origin" });
    const data = (await r.json()) as T;
    if (typeof data.message !== "string") data.message = r.ok ? "" : `HTTP ${r.status}`;
    return data;
  } catch (e) {
    return { success: false, message: String(e) } as T;
  }
}

export type Message = { type: string; [key: string]: unknown };

/** The server's messages, in order; `onClose` when the server has gone (no reconnection:
 * a page of a server that stopped must say so, not pretend). */
export function connect(onMessage: (m: Message) => void, onOpen: () => void, onClose: () => void): WebSocket {
  const url = `ws://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : "");
  const ws = new WebSocket(url);
  ws.onopen = onOpen;
  ws.onclose = onClose;
  ws.onmessage = (ev) => onMessage(JSON.parse(String(ev.data)) as Message);
  return ws;
}
