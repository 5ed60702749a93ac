"""The interactive explorer in the browser (viser), started from a script.

Opens a server on ``port`` (0: any free port) and serves until Ctrl-C; every browser that opens the
printed address gets its own sliders and 3-D scene. ``serve=False`` starts it and stops at once
(the tests do that).

    python examples/05_explorer.py
"""

from __future__ import annotations

import time

from paraspace.app.explorer import Explorer


def main(port: int = 8080, serve: bool = True) -> str:
    explorer = Explorer(host="127.0.0.1", port=port).start()
    url = explorer.url
    print(f"paraspace explorer: {url}", flush=True)
    try:
        while serve:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        explorer.stop()
    return url


if __name__ == "__main__":
    main()
