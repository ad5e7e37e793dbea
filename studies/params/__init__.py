"""Studies of the parametrizations: the mpmath reference maps and the accuracy study."""
