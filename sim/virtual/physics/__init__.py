"""The physics the simulated devices compute: the scene's optics (`optics`: material,
source and reference through the radiometric chain), the sensor (`sensor`), counter-based
random streams (`streams`) and the Poisson quantile (`poisson`)."""

#: Imported by module (`sim.virtual.physics.streams`, …): re-exports here would make the scene
#: and the fault rules, which use the streams, import one another in a cycle.
__all__: list[str] = []
