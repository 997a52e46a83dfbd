"""embodichain-functors: the standard functor library of embodichain, as a plugin.

Configs name the functors by their registered names (``"func": "randomize_light"``)
or import them::

    import embodichain_functors.randomization as rand
    import embodichain_functors.events as events
    import embodichain_functors.observations as obs
    import embodichain_functors.rewards as rewards
    import embodichain_functors.actions as actions

Each kind has one home, the module above (a package re-exports its topic modules);
:mod:`embodichain_functors.catalogue` registers every functor with one line. See
docs/functors.md (section "Adding a functor") and docs/functor_catalogue.md.
"""

__version__ = "0.1.0"
