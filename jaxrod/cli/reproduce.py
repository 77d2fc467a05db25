"""`jaxrod reproduce`: the paper's experiments."""

from __future__ import annotations

from ._common import _fail


def _cmd_reproduce(args) -> int:
    import jax

    jax.config.update("jax_enable_x64", True)
    from ..reproduce import reproduce

    try:
        res = reproduce(args.which, args.out, quick=args.quick, progress=not args.quiet, model=args.model, n=args.n)
    except ValueError as err:
        _fail(str(err))
    print(f"wrote {args.out}/results.json and figures under {args.out}/<experiment>/")
    for name, r in res.items():
        print(f"  {name}: {r.get('seconds', '?')} s")
    return 0

