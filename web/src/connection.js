// The WebSocket to `vdiso serve`: JSON text messages and binary ArrayBuffers in, binary out.
// The token comes from the page's own URL (?token=T); the server also sets it as a cookie,
// which the upgrade request carries, so either suffices.

// follow: a session id to follow (follow mode), or null.
export function webSocketUrl(location, follow = null) {
  const token = new URLSearchParams(location.search).get('token');
  const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const query = new URLSearchParams();
  if (token !== null) query.set('token', token);
  if (follow !== null) query.set('follow', follow);
  const text = query.toString();
  return `${scheme}//${location.host}/ws${text ? `?${text}` : ''}`;
}

export class Connection {
  // handlers: { text(string), binary(arrayBuffer), close(closeEvent) }
  constructor(url, handlers) {
    this.socket = new WebSocket(url);
    this.socket.binaryType = 'arraybuffer';
    this.socket.addEventListener('message', (event) => {
      if (typeof event.data === 'string') handlers.text(event.data);
      else handlers.binary(event.data);
    });
    this.socket.addEventListener('close', (event) => handlers.close(event));
  }

  get isOpen() {
    return this.socket.readyState === WebSocket.OPEN;
  }

  send(buffer) {
    this.socket.send(buffer);
  }
}
