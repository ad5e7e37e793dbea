"""The simulated devices: virtual motors (`motors`), a virtual detector and light source
(`detector`), and the factory that builds them as one instrument (`instrument`)."""
