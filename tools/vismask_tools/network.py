"""The network model of docs/BENCHMARKS.md and docs/CLUSTER.md: 16 nodes,
Open MPI over TCP on a switched 1 Gbit/s network. Each collective of a
solve (run.json `collectives`: the first totals' AllGather, then one
AllToAll a round that carries the packets and the reports) is a message
from every rank to each of the others, posted at once, counted as if they
went one after another; the bytes are spread evenly over the nodes' links."""

NODES = 16
LATENCY, BANDWIDTH = 100e-6, 117e6  # per message step; per link, bytes/s (1 Gbit TCP)
STEPS16 = NODES - 1                 # message steps a collective at 16 ranks


def latency_seconds(result):
    """The message steps' time of a 16-rank run with run.json `result`."""
    return result["collectives"] * STEPS16 * LATENCY


def transfer_seconds(result):
    """The time its bytes take on one node's link."""
    return result["bytes_sent"] / NODES / BANDWIDTH


def network_seconds(result):
    return latency_seconds(result) + transfer_seconds(result)
