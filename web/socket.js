// The pages' connection to nerfpt: a WebSocket that is opened again, with backoff (0.5 s doubling to 5 s), when
// it drops (nerfpt restarted, a connection reset), for as long as the page is open. The server greets each new
// socket as a new page; what a page must re-send after a reconnect is its own (its handlers do that).
const retryFirstMs = 500, retryMaxMs = 5000;

// onOpen(): a socket is open; onMessage(event); onDrop(closeEvent, nextTryMs): it dropped and will be opened
// again in nextTryMs. Nothing connects until connect() is called (after the handlers' state exists).
export function reconnectingSocket({ onOpen, onMessage, onDrop }) {
  let ws = null, retryMs = retryFirstMs;
  let leaving = false;  // the page is being unloaded: its socket closes on purpose
  function connect() {
    ws = new WebSocket(`ws://${location.host}/ws${location.search}`);
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => { retryMs = retryFirstMs; onOpen(); };
    ws.onmessage = onMessage;
    ws.onclose = (e) => {
      if (leaving || e.target !== ws) return;  // unloading, or a socket already replaced
      onDrop(e, retryMs);
      setTimeout(connect, retryMs);
      retryMs = Math.min(2 * retryMs, retryMaxMs);
    };
  }
  window.addEventListener('pagehide', () => { leaving = true; });
  window.addEventListener('pageshow', (e) => {  // back from the back/forward cache: its socket was closed
    leaving = false;
    if (e.persisted && ws && ws.readyState === WebSocket.CLOSED) connect();
  });
  return {
    connect,
    isOpen: () => ws !== null && ws.readyState === WebSocket.OPEN,
    send: (text) => ws.send(text),
  };
}
