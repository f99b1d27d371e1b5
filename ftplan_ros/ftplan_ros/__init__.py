"""ftplan: failure-tolerant motion planning for kinematically redundant arms."""
