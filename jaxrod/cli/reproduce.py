"""`jaxrod reproduce`: the paper's experiments."""

from __future__ import annotations

from ._common import _fail


def _cmd_reproduce(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from ..reproduce import PAPER, reproduce

    which = args.which
    if "all" in which:  # the paper's, and lockup if named beside it
        which = list(PAPER) + [w for w in which if w not in PAPER and w != "all"]
    try:
        res = reproduce(which, args.out, quick=args.quick, progress=not args.quiet)
    except ValueError as err:
        _fail(str(err))
    print(f"wrote {args.out}/results.json and figures under {args.out}/<experiment>/")
    for name, r in res.items():
        print(f"  {name}: {r.get('seconds', '?')} s")
    return 0

