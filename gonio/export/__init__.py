"""Writers of reconstructed BRDFs in other programs' formats."""
