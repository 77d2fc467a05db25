"""The options of the sweep commands (`jaxrod map`) that run them on several processes under
`jax.distributed`, and joining the run before any JAX computation."""

from __future__ import annotations

import argparse

from ._common import _fail, _nonnegative_int, _positive_int

# library argument -> option (the library names the setting an error is about)
_OPTIONS = {"coordinator_address": "--coordinator", "num_processes": "--num-processes", "process_id": "--process-id"}


def _host_port(text: str) -> str:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r} is not of the form HOST:PORT (port 1-65535)")
    return text


def _add_distributed_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group(
        "several processes (jax.distributed: each process runs its share of the members and writes it "
        "to --out, which all of them must share; docs/sweeps.md: Many processes)")
    g.add_argument("--distributed", action="store_true",
                   help="join a run whose settings come from the cluster's environment (SLURM, Open MPI, "
                        "Kubernetes; as jax.distributed.initialize() detects them); the options below override")
    g.add_argument("--coordinator", dest="coordinator_address", type=_host_port, default=None, metavar="HOST:PORT",
                   help="address of process 0, which serves the run (any free port)")
    g.add_argument("--num-processes", dest="num_processes", type=_positive_int, default=None, metavar="N",
                   help="number of processes")
    g.add_argument("--process-id", dest="process_id", type=_nonnegative_int, default=None, metavar="I",
                   help="this process's index, 0 <= I < N")
    g.add_argument("--chunk-size", dest="chunk_size", type=_positive_int, default=None, metavar="M",
                   help="members per chunk, the unit of work dealt to the processes and written to --out "
                        "(default: a whole map of up to 1024 members, one chunk)")


def _start_distributed(args) -> None:
    """Join the `jax.distributed` run the options describe (nothing without them): explicit
    settings come all three together, or with --distributed, which takes the others from the
    environment. One line and exit code 2 on a bad or missing setting."""
    given = {opt: getattr(args, name) for name, opt in _OPTIONS.items()}
    if not args.distributed and all(v is None for v in given.values()):
        return
    if not args.distributed:
        missing = [opt for opt, v in given.items() if v is None]
        if missing:
            _fail(f"argument {missing[0]}: required with {', '.join(o for o in given if o not in missing)} "
                  "(or add --distributed to take it from the cluster's environment).")
    if args.process_id is not None and args.num_processes is not None and args.process_id >= args.num_processes:
        _fail(f"argument --process-id: {args.process_id} is invalid: expected < --num-processes "
              f"({args.num_processes}).")
    from ..distributed import initialize

    try:
        initialize(args.coordinator_address, args.num_processes, args.process_id)
    except ValueError as err:
        msg = str(err)
        opt = next((o for name, o in _OPTIONS.items() if msg.startswith(name)), "--distributed")
        _fail(f"argument {opt}: {msg}")
    except RuntimeError as err:  # the coordinator was not reached in time
        _fail(f"argument --coordinator: cannot join the run: {str(err).strip().splitlines()[0]}")
