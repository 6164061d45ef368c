"""A local Dask engine starts quietly beside another one (issue 45's clean exits and messages)."""

from __future__ import annotations

import socket
import warnings

from cable_ocp.sweep.runner import engine


def test_a_local_engine_beside_another_on_the_dashboard_port_warns_nothing():
    holder = socket.socket()
    try:
        try:
            holder.bind(("", 8787))  # Dask's dashboard port, as another engine holds it
            holder.listen()
        except OSError:  # something holds it already: the same case
            pass
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            client, cluster = engine(None, 1, processes=False)
            client.close()
            cluster.close()
    finally:
        holder.close()
    said = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert not [text for text in said if "already in use" in text], said
