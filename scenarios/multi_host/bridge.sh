# Sourced by the multi-host scripts (run.sh, sweep_cluster.sh): "hosts" as Linux network
# namespaces, each with a veth pair into a bridge in a "switch" namespace of its own. The
# bridge is attached to no interface of this machine's own namespace, and the hosts get
# addresses on one /24 only, with no default route: nothing can leave the namespaces made.

# make_switch SWITCH: the switch namespace and its bridge br0.
make_switch() {
    ip netns add "$1"
    ip -n "$1" link add br0 type bridge
    ip -n "$1" link set br0 up
}

# add_host SWITCH NS ADDRESS: namespace NS, its eth0 (ADDRESS/24) plugged into SWITCH's
# bridge (the switch end is named NS-s), and its loopback up.
add_host() {
    ip netns add "$2"
    ip link add "$2-s" netns "$1" type veth peer name eth0 netns "$2"
    ip -n "$1" link set "$2-s" master br0 up
    ip -n "$2" link set lo up
    ip -n "$2" addr add "$3/24" dev eth0
    ip -n "$2" link set eth0 up
}
