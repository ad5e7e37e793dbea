"""The physics the simulated devices compute: the scene's optics (`optics`: material,
source and reference through the radiometric chain), the sensor (`sensor`), counter-based
random streams (`streams`) and the Poisson quantile (`poisson`)."""
